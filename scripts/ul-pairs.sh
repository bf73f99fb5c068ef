#!/bin/bash
# Interleaved small-strain / updated-Lagrangian pairs of `wendel bench ul`'s 3d-voce case (issue 14): the code
# of BASE (a copy of another tree with its build/plugins, e.g. `git archive main | tar -x -C DIR` plus
# `cp -r build DIR`) and of this tree alternating, each pair under the machine lock; one JSON line per pair
# (increment ratio = (assembly + linear_solve + constitutive) per increment, UL over SS, as the bench computes it).
# Usage: scripts/ul-pairs.sh BASE ROUNDS H [OUT]   (from the repository root, after `make setup`; H 0.125: 2.3k
# DoFs, 0.0625: 12k; OUT default results/ul-pairs.jsonl; the runs go to results/ul-pairs/)
set -eu
cd "$(dirname "$0")/.."
base=$(cd "$1" && pwd); rounds=$2; h=$3; out=${4:-results/ul-pairs.jsonl}
mkdir -p results/ul-pairs
touch /tmp/wendel-heavy.lock
pair() {  # TAG PYTHONPATH
    flock /tmp/wendel-heavy.lock env PYTHONPATH="$2" .venv/bin/python - "$1" "$h" "$PWD/results/ul-pairs" <<'PY' >> "$out"
import json, sys
from pathlib import Path
from wendel.bench import WORKFLOWS, run_fresh
from wendel.bench.ul import _necking_bar_steel
from wendel.scene import load
tag, h, root = sys.argv[1], float(sys.argv[2]), Path(sys.argv[3])
path, row = WORKFLOWS / "ul-tension-3d.toml", {"tag": tag, "h": h}
for kind, t in (("small-strain", "ss"), ("updated-lagrangian", "ul")):
    scene = load(path)
    scene.geometry.h, scene.kinematics.kind, scene.loading.steps = h, kind, 5
    scene.boundary["top"].uz = 0.05
    _necking_bar_steel(scene)
    scene.output.png = scene.output.vtu = False
    s = run_fresh(scene, path, root / f"{tag}-{h:g}-{kind}")
    ph = s["wall_time_by_phase"]
    row.update({"dofs": s["dofs"], f"newton_{t}": s["newton_iterations"],
                f"increment_{t}": (ph["assembly"] + ph["linear_solve"] + ph["constitutive"]) / s["increments"],
                f"constitutive_{t}": ph["constitutive"] / s["increments"]})
row["increment_cost_ratio"] = row["increment_ul"] / row["increment_ss"]
print(json.dumps(row))
PY
}
for r in $(seq 1 "$rounds"); do
    pair base "$base/driver"
    pair this "$PWD/driver"
done
tail -n $((2 * rounds)) "$out"
