"""Command line: ``wendel run | study | check | keys | sweep | oxley | bench``.

Exit codes: 0 done, 1 the run failed (FreeFEM error, no convergence, disk full), 2 bad input (scene,
options), 130 interrupted (Ctrl-C or SIGTERM; the run resumes with ``wendel run --resume DIR``).
Only what a command needs is imported: ``wendel check`` and ``wendel keys`` never load the solver side.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from pathlib import Path

from . import __version__


MESH_CACHE_HELP = ("reuse the initial meshes of earlier runs from this folder (content-addressed; "
                   "also WENDEL_MESH_CACHE=DIR)")


def ranks_option(text: str) -> int:
    """``--np``: an integer from 1 to 64 (numerics.ranks' range)."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if not 1 <= n <= 64:
        raise argparse.ArgumentTypeError(f"{n} is not a number of ranks from 1 to 64")
    return n


def printable(text: str) -> str:
    r"""``text`` with control characters escaped, so scene strings cannot drive the terminal.

    >>> printable("a\x1b[2Jb\tc")
    'a\\x1b[2Jb\tc'
    """
    return "".join(c if c.isprintable() or c in "\n\t" else repr(c)[1:-1] for c in str(text))


def _terminate(signum, frame):
    raise KeyboardInterrupt        # SIGTERM stops a run like Ctrl-C: FreeFEM too, resumable, exit 130


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="wendel", description="Thermo-elastoplastic contact simulations "
                                     "with FreeFEM and gmsh.")
    parser.add_argument("--version", action="version", version=f"wendel {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("run", help="run a scene")
    p.add_argument("scene", nargs="?", help="scene file (TOML)")
    p.add_argument("--np", type=ranks_option, help="MPI ranks, 1 to 64 (overrides numerics.ranks; >1 uses ffddm)")
    p.add_argument("--smoke", action="store_true", help="run at the scene's tiny smoke size")
    p.add_argument("--out", type=Path, help="run folder (default results/<scene>/<time>)")
    p.add_argument("--resume", type=Path, metavar="RUN_DIR", help="continue a run from its last checkpoint")
    p.add_argument("--mesh-cache", type=Path, metavar="DIR", help=MESH_CACHE_HELP)

    p = sub.add_parser("study", help="error against run time over refined meshes")
    p.add_argument("scene")
    p.add_argument("--levels", type=int, default=3, help="number of meshes (h, h/2, ...)")
    p.add_argument("--mesh-cache", type=Path, metavar="DIR", help=MESH_CACHE_HELP)
    p.add_argument("--smoke", action="store_true", help="start from the smoke size")
    p.add_argument("--np", type=ranks_option)
    p.add_argument("--out", type=Path)

    p = sub.add_parser("check", help="validate a scene file without running it")
    p.add_argument("scene", nargs="+")

    p = sub.add_parser("oxley", help="the extended Oxley model's prediction of a cutting scene (milliseconds)")
    p.add_argument("scene", help="scene file with a [cutting] table")
    p.add_argument("--out", type=Path, help="folder of oxley.json and oxley.csv (default results/<scene>/oxley)")
    p.add_argument("--no-png", action="store_true", help="no picture of the solution (oxley.png)")

    p = sub.add_parser("keys", help="print the scene keys (type, default, unit, range) as a Markdown table")
    p.add_argument("--update", type=Path, metavar="README", help="rewrite the table in this file instead")

    p = sub.add_parser("bench", help="benchmarks; results into results/bench/",
                       formatter_class=argparse.RawTextHelpFormatter)     # names are not wrapped at hyphens
    p.add_argument("names", nargs="*", help="benchmarks to run (default: all of these):\n"
                   "  axisymmetric, cylinder, dg, dg-3d, dg-plastic, drilling, elasticity, friction, obstacle, petsc, remesh,\n"
                   "  step42, sweep, thermal, ul,\n"
                   "  kernels (compiled element kernels against the varf forms on the ball, 2 min),\n"
                   "  necking (Simo's necking bar on 3 meshes, with and without F-bar),\n"
                   "  oxley, oxley-domain, oxley-kienzle (the analytic orthogonal cut);\n"
                   "only when named: step42-dealii, step42-pair (deal.II and wendel interleaved, about 8 minutes),\n"
                   "  step42-accuracy (the time to a force within 2 %% of the converged one, about 7 minutes),\n"
                   "  overhead, gmsh3d, meshcache (the ball with a cold and a warm mesh cache, about 3 minutes),\n"
                   "  sweep-warm (20 smoke runs of a local sweep, forked warm and as fresh interpreters, about 2 minutes),\n"
                   "  ranks (the ball on 1 and 2 PETSc ranks, interleaved, about 4 minutes),\n"
                   "  cutting (the steel and the titanium cut to their steady state, about 55 minutes),\n"
                   "  cutting-adiabatic, cutting-isothermal (the prototype steel cut, about 15 minutes each),\n"
                   "  cutting-mesh (the FE cut at 3 edge resolutions and 2 steps, about an hour), cutting-fbar,\n"
                   "  cutting-steady (the FE cut to 1.2 mm, about 10-15 minutes), cutting-steady-fbar (the same with F-bar),\n"
                   "  cutting-steady-mesh (the F-bar cut with conduction to 1.2 mm at r/2, r/3, r/4: 1-3 h each),\n"
                   "  cutting-long (the FE cut to 2.4 mm, about 25 minutes),\n"
                   "  direct (UMFPACK64 against MUMPS on the cut, a 2D and a 3D scene, about 10 minutes),\n"
                   "  cutting-levers (a 200 um F-bar cut with conduction as it is, again, with 4 levers and sessions\n"
                   "    24's and 25's taken back, 30 minutes), cutting-paths (that cut as it is and as before session 25\n"
                   "    (WENDEL_BENCH_BEFORE=24: 24; WENDEL_BENCH_LEVER: with one of cutting-levers' levers)\n"
                   "    on 4 tool paths differing in their 13th digit, 20 minutes),\n"
                   "  cutting-heat (the FE cut to 400 um adiabatic and with conduction, about 20 minutes),\n"
                   "  cutting-ti (the titanium FE cut on the graded mesh, about 10 minutes),\n"
                   "  cutting-kienzle (the FE Kienzle campaign: 8 cuts by wendel sweep, about 40 core minutes),\n"
                   "  drilling-3d (the 3D deep bore, all 50 removal steps, about 7 minutes),\n"
                   "  necking-fine (the necking bar on a finer and on remeshed meshes, about 4 minutes)")
    p.add_argument("--quick", action="store_true", help="small sizes only")
    p.add_argument("--out", type=Path, metavar="DIR", help="results (and work folders) into DIR instead of "
                   "results/bench/ (two benches at once each into its own)")

    p = sub.add_parser("sweep", help="campaigns: a plan of runs, locally or on SLURM (see wendel.sweep)")
    from .sweep.cli import add_arguments as sweep_arguments
    sweep_arguments(p)
    p.add_argument("--mesh-cache", type=Path, metavar="DIR", help=MESH_CACHE_HELP)

    args = parser.parse_args(argv)
    if getattr(args, "mesh_cache", None):     # inherited by a sweep's runs (local and SLURM)
        os.environ["WENDEL_MESH_CACHE"] = str(args.mesh_cache.resolve())
    if args.command == "run" and args.resume is None and args.scene:
        _prestart_picture(Path(args.scene))
    from .errors import DiskFull, Interrupted, StepCutError
    from .freefem import FreeFemError, NewtonFailure
    from .scene import SceneError
    if args.command in ("run", "study"):
        signal.signal(signal.SIGTERM, _terminate)
    try:
        if args.command == "check":
            from .scene import load
            for s in args.scene:
                scene = load(s)
                print(printable(f"{s}: ok ({scene.description}; blocks: {', '.join(scene.blocks) or 'elastic'})"))
            return 0
        if args.command == "run":
            from .loop import run
            if args.resume is None and args.scene is None:
                parser.error("run needs a scene file or --resume RUN_DIR")
            if args.resume is not None:
                ignored = [f"the scene file {args.scene}"] * bool(args.scene) + ["--np"] * (args.np is not None) \
                    + ["--smoke"] * args.smoke + ["--out"] * (args.out is not None)
                if ignored:
                    print(printable(f"wendel: ignored with --resume (the run goes on with its own settings): "
                                    f"{', '.join(ignored)}"))
            root = run(args.scene or "", smoke=args.smoke, ranks=args.np, out=args.out, resume=args.resume)
            _print_summary(root)
            return 0
        if args.command == "study":
            from .results.study import study
            root = study(args.scene, levels=args.levels, smoke=args.smoke, ranks=args.np, out=args.out)
            print(f"study written to {root}")
            return 0
        if args.command == "sweep":
            from .sweep.cli import command as sweep_command
            return sweep_command(args)
        if args.command == "oxley":
            from .cutting.scene import analytic, summary_lines
            record, out = analytic(args.scene, args.out, picture=not args.no_png)
            print("\n".join(summary_lines(record)))
            print(f"written: {out / 'oxley.json'}, {out / 'oxley.csv'}, tool polygon {out / 'tool.txt'}")
            return 0
        if args.command == "keys":
            from .scene.schema import keys_table, update_readme
            if args.update:
                print(f"{args.update}: {'updated' if update_readme(args.update) else 'up to date'}")
            else:
                print(keys_table())
            return 0
        if args.command == "bench":
            from .bench import bench
            root = bench(args.names, quick=args.quick, out=args.out)
            print(f"benchmarks written to {root}")
            return 0
    except SceneError as exc:
        print(printable(f"wendel: bad scene:\n{exc}"), file=sys.stderr)
        return 2
    except (FileNotFoundError, ValueError, KeyError) as exc:
        print(printable(f"wendel: bad input: {exc}"), file=sys.stderr)
        return 2
    except (FreeFemError, NewtonFailure, StepCutError, DiskFull) as exc:
        print(printable(f"wendel: run failed: {exc}"), file=sys.stderr)
        return 1
    except Interrupted as exc:
        print(printable(f"wendel: {exc}"), file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print("wendel: interrupted", file=sys.stderr)
        return 130
    return 0


def _prestart_picture(scene: Path) -> None:
    """Start the run's picture process before the driver imports its modules (issue 20): its own imports
    (0.55 s) then overlap theirs. Only for a scene file that asks for a picture (``output.png``, default on)
    and is a quasi-static run (not drilling or cutting); the run takes it (``pictures.painter``)."""
    import tomllib

    try:
        table = tomllib.loads(scene.read_text())
        if table.get("output", {}).get("png", True) is not True or {"drilling", "cutting"} & set(table):
            return
    except (OSError, ValueError, AttributeError):       # the run reports a bad file
        return
    from .results import pictures

    pictures.prestart()


def _print_summary(root: Path) -> None:
    import json

    s = json.loads((root / "summary.json").read_text())
    print(f"done: {s['increments']} increments, {s['newton_iterations']} Newton iterations, "
          f"{s['dofs']} DoFs on {s['ranks']} rank(s), {s['wall_time']:.2f} s "
          f"(start-up and I/O {100 * (s['share_startup_and_io'] or 0):.0f}%)")
    errors = dict(s.get("errors") or {})
    if "error_l2_relative" in errors and "error_h1_relative" in errors:
        print(f"relative error against the analytic reference: L2 {errors['error_l2_relative']:.3e}, "
              f"H1 {errors['error_h1_relative']:.3e}")
    errors = {k: v for k, v in errors.items() if k.removesuffix("_relative") not in ("error_l2", "error_h1")}
    if errors:
        print("errors against the closed form: " + ", ".join(f"{k.removeprefix('error_')} {v:.3e}"
                                                             for k, v in errors.items()))
    for w in s.get("warnings") or []:
        print(printable(f"warning: {w}"))
    print(f"results: {root}  (ParaView: {root / 'results.pvd'})")


def leave(code: int | None) -> None:
    """End the process with ``code`` without the interpreter's teardown of its 500-odd modules (issue 20:
    0.09-0.24 s after a smoke run's last file, measured with ``os._exit`` against ``sys.exit``). Only after
    ``main`` returned: every thread is joined and every file closed by then; the atexit functions still run
    and the standard streams are flushed."""
    import atexit

    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    atexit._run_exitfuncs()
    os._exit(code or 0)


def entry() -> None:
    """The ``wendel`` console script: :func:`main`, then :func:`leave` (an error that escapes ``main``, and
    ``SystemExit`` from argparse, end the process the usual way)."""
    leave(main())


if __name__ == "__main__":
    entry()
