#!/bin/bash
# Two facts a FreeFEM that takes launch after launch would rest on (issue 20, README "Time outside the solve",
# session 34): a script may assign ARGV's entries (getARGV then reads the new value) but not resize ARGV, and
# func, mesh and fespace declarations compile and run inside a loop body.
# Usage: scripts/freefem-loop-facts.sh   (from the repository root, after `make setup`)
set -u
cd "$(dirname "$0")/.."
. edp/env.sh
export OMPI_MCA_ess_singleton_isolated=1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cat > "$tmp/argv.edp" <<'EDP'
include "getARGV.idp"
cout << "ARGV entries: " << ARGV.n << ", -foo before: " << getARGV("-foo", 1.5);
ARGV[ARGV.n - 2] = "-foo";
ARGV[ARGV.n - 1] = "7.25";
cout << ", after assigning two entries: " << getARGV("-foo", 1.5) << endl;
EDP
cat > "$tmp/resize.edp" <<'EDP'
ARGV.resize(ARGV.n + 2);
EDP
cat > "$tmp/loop.edp" <<'EDP'
for (int k = 0; k < 2; ++k) {
    func real g(real x) { return x * (k + 1); }
    mesh Th = square(4 + k, 4);
    fespace Vh(Th, P1);
    Vh u = g(x);
    cout << "loop pass " << k << ": " << Th.nv << " vertices, integral of u " << int2d(Th)(u) << endl;
}
EDP
FreeFem++-mpi -nw -v 0 "$tmp/argv.edp" pad1 pad2 2>&1 | grep "ARGV entries"
if FreeFem++-mpi -nw -v 0 "$tmp/resize.edp" > "$tmp/resize.log" 2>&1; then
    echo "ARGV.resize: compiled and ran"
else
    echo "ARGV.resize: refused ($(grep -m1 -o 'Compile error.*' "$tmp/resize.log" || echo "exit code $?"))"
fi
FreeFem++-mpi -nw -v 0 "$tmp/loop.edp" 2>&1 | grep "loop pass"
