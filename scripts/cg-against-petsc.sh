#!/bin/bash
# The scenes that used Jacobi-CG until session 12 (ball-indent, hertz-3d, stamp-indent) at their default size with
# Jacobi-CG, with PETSc-ML (numerics.solver = "petsc") and, for the plastic ones, PETSc-ML with the compiled kernels
# (numerics.assembly = "compiled", their default since session 12): ROUNDS interleaved rounds, one row per run
# (issue 19).
# Usage: scripts/cg-against-petsc.sh [OUT_DIR] [ROUNDS]   (run it under the heavy lock on a shared machine)
set -euo pipefail
cd "$(dirname "$0")/.."
S=$(realpath -m "${1:-results/cg-against-petsc}")
ROUNDS=${2:-2}
mkdir -p "$S"
cp -r workflows/images "$S/"          # the stamp's image, found relative to the scene
for round in $(seq "$ROUNDS"); do
  for scene in ball-indent hertz-3d stamp-indent; do
    for variant in cg petsc petsc-compiled; do
      grep -q '^\[plasticity\]' "workflows/$scene.toml" || [ "$variant" != petsc-compiled ] || continue
      f=$S/$scene-$variant.toml
      # the scene's own solver and assembly lines replaced by the variant's
      sed -e "/^assembly = /d" -e "s/^solver = .*/solver = \"${variant%%-*}\"/" "workflows/$scene.toml" > "$f"
      [ "$variant" != petsc-compiled ] || sed -i 's/^solver = "petsc"/solver = "petsc"\nassembly = "compiled"/' "$f"
      out=$S/run-$scene-$variant-$round
      rm -rf "$out"
      .venv/bin/wendel run "$f" --out "$out" > "$out.log" 2>&1 || { echo "$scene $variant failed: $(tail -1 "$out.log")"; continue; }
      .venv/bin/python - "$out" "$scene" "$variant" "$round" <<'PY'
import json, sys
out, scene, variant, rnd = sys.argv[1:]
s = json.load(open(out + "/summary.json"))
ph = s["wall_time_by_phase"]
print(f"{scene} {variant} round {rnd}: {s['dofs']} DoFs, {s['newton_iterations']} Newton, wall {s['wall_time']:.2f} s, "
      f"assembly + solve + constitutive {ph['assembly'] + ph['linear_solve'] + ph['constitutive']:.2f} s, "
      f"contact force {s['last_increment'].get('contact_force')!r}")
PY
    done
  done
done
