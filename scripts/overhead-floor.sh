#!/bin/bash
# The floor of a smoke-size run, piece by piece (issue 20): median wall time of 7 runs of each command.
# Usage: scripts/overhead-floor.sh   (from the repository root, after `make setup`; under the machine lock)
set -u
cd "$(dirname "$0")/.."
export FF_INCLUDEPATH="/usr/include/freefem++/idp;$PWD/edp" FF_LOADPATH="$PWD/build/plugins;/usr/lib/freefem++/mpi" \
    OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_pml=ob1 OMPI_MCA_btl=self,vader \
    OMPI_MCA_rmaps_base_oversubscribe=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 OMPI_MCA_ess_singleton_isolated=1
tmp=$(mktemp -d)
echo 'cout << 1 << endl;' > "$tmp/empty.edp"
(cat workflows/smoke.toml; printf '\n[output]\npng = false\n') > "$tmp/nopng.toml"
median() { sort -n | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
t() {
    local name="$1"; shift
    for i in 1 2 3 4 5 6 7; do
        rm -rf "$tmp/run"
        a=$(date +%s%N); "$@" > /dev/null 2>&1; b=$(date +%s%N)
        echo $(( (b - a) / 1000000 ))
    done | median | xargs -I{} echo "{} ms  $name"
}
t "python -c pass" .venv/bin/python -c pass
t "python -c 'import numpy'" .venv/bin/python -c "import numpy"
t "python -c 'from wendel.loop import run'" .venv/bin/python -c "from wendel.loop import run"
t "python: the picture process's imports (matplotlib Agg, pyplot, meshio)" \
    .venv/bin/python -c "import matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot, meshio"
t "FreeFem++ (no MPI), empty script" FreeFem++ -nw -v 0 "$tmp/empty.edp"
t "FreeFem++-mpi singleton, empty script" FreeFem++-mpi -nw -v 0 "$tmp/empty.edp"
t "FreeFem++-mpi singleton, edp/mechanics.edp 2D elastic compiled (no -out: stops)" \
    FreeFem++-mpi -nw -v 0 edp/mechanics.edp -Ddimension=2 -DPk=P1
t "wendel run workflows/smoke.toml --smoke" .venv/bin/wendel run workflows/smoke.toml --smoke --out "$tmp/run"
t "the same with [output] png = false" .venv/bin/wendel run "$tmp/nopng.toml" --smoke --out "$tmp/run"
rm -rf "$tmp"
