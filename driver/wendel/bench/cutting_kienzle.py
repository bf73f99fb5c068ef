"""``wendel bench cutting-kienzle``: Kienzle's k_c1.1 and m_c of AISI 1045 from FE cuts (issue 17).

Runs the campaign ``workflows/campaigns/cutting-kienzle.toml`` with ``wendel sweep`` (local; its folder
results/sweeps/cutting-kienzle/, so a sweep run or interrupted before is resumed, not repeated, and a failed cut tried
again: about 40 core minutes from scratch) and fits F_c = b k_c1.1 h^(1 - m_c) to each cut's steady F_c (the mean over its last h of
travel) per (speed, rake), beside the Oxley model's fit at the same conditions and the catalogue constants
(:mod:`wendel.cutting.fe_campaign`). Rows: one per cut (``kind = "cut"``: F_c FE and Oxley, the window, the
spread and drift of the remesh-cycle means in it) and one per fit (``kind = "fit"``); the picture
results/bench/cutting-kienzle.png (F_c against h, log-log). ``--quick`` reads the sweep folder as it stands
(the cuts done so far) without running anything.
"""

from __future__ import annotations

from pathlib import Path

from . import WORKFLOWS, register, volumetric

SWEEP = WORKFLOWS / "campaigns" / "cutting-kienzle.toml"


@register("cutting-kienzle")
def cutting_kienzle(quick: bool, workdir: Path) -> list[dict]:
    """The campaign as written (its scene's plain P1 cells); ``WENDEL_BENCH_FBAR`` 1 or 0: a copy with
    ``"cutting.volumetric"`` = ``"fbar"`` or ``"cell"`` in its ``[set]`` (results/bench/work/cutting-kienzle/
    cutting-kienzle-<fbar|cell>.toml; sweep folder results/sweeps/cutting-kienzle-<fbar|cell>/, picture
    cutting-kienzle-<fbar|cell>.png)."""
    from ..cutting import fe_campaign
    from ..sweep import run_sweep, sweep_root

    sweep, tag = SWEEP, ""
    vol = volumetric(None)          # None: the campaign as written
    if vol:
        sweep, tag = _with_volumetric(workdir, vol), f"-{vol}"
    if not quick:
        run_sweep(sweep, quiet=True, log=lambda *_: None)
    root = sweep_root(sweep)
    cuts = fe_campaign.points(root)
    fits = fe_campaign.compare(cuts, "aisi1045")
    fe_campaign.plot(workdir.parents[1] / f"cutting-kienzle{tag}.png", cuts, fits,
                     f"AISI 1045: FE cuts (edge r/2{', ' + tag[1:] if tag else ''}, last h of 2.67 h) against Oxley, catalogues")
    return [{"kind": "cut", **r} for r in cuts] + [{"kind": "fit", **f} for f in fits]


def _with_volumetric(workdir: Path, vol: str) -> Path:
    """A copy of the campaign with ``"cutting.volumetric" = vol`` in its ``[set]`` and its scene path made absolute."""
    import tomllib

    import tomli_w
    d = tomllib.loads(SWEEP.read_text())
    d["scene"] = str((SWEEP.parent / d["scene"]).resolve())
    d["set"]["cutting.volumetric"] = vol
    workdir.mkdir(parents=True, exist_ok=True)
    out = workdir / f"cutting-kienzle-{vol}.toml"
    out.write_text(tomli_w.dumps(d))
    return out
