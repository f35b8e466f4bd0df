"""Headless entry points.

    gpusph-run SCENE [--run-config NAME|FILE ...] [--set key=value ...] --out DIR
    gpusph-analyze DIR [--charts DIR] [--reference DIR]     (a recording, or a study's results folder)
    gpusph-analyze --repair BAG                             (a killed recording made readable again)
    gpusph-sweep STUDY [--scheduler ADDRESS] [--out DIR]
    gpusph-plan SCENE [--run-config NAME|FILE ...] [--set key=value ...] [--no-reductions | --estimate]
    gpusph-stability [--out DIR] [--workers N] [--device DEV] [--kernels ...] ... [--report]

(also ``python -m gpusph_ros.cli run|analyze|sweep|plan|stability ...``). SCENE is a built-in scene name or a YAML
file; run settings layer as scenes.settings describes. Exit status: 0 done, 2 the run failed a
health check or was interrupted (its recording is closed and readable), 1 bad input.
"""
import argparse
import signal
import sys
import threading
import time


class Progress:
    """A run's progress as tqdm draws it: simulated time against the end time, the elapsed wall time
    and the ETA, then steps, steps/s, MIPPS and the excluded particles. On a terminal one bar is
    redrawn in place; elsewhere (a log) a line is written about every 5% of the run."""

    FORMAT = "{l_bar}{bar}| t = {n:.3f} / {total:g} s [{elapsed}, ETA {remaining}{postfix}]"

    def __init__(self, run, stream=sys.stdout):
        from tqdm import tqdm

        self.tty = stream.isatty()
        self.stream = stream
        self.bar = tqdm(total=run.output.end_time, file=stream, bar_format=self.FORMAT, dynamic_ncols=True,
                        ascii=not self.tty, disable=not self.tty, leave=True)
        self.every = max(1, run.n_outputs // 20)
        self.start = time.perf_counter()

    def postfix(self, run) -> str:
        s, e = run.solver, run.tally
        text = f"{s.steps} steps, {s.steps / max(run.wall, 1e-9):.1f} steps/s, {run.mipps():.3f} MIPPS"
        return text + (f", excluded {e['excluded_particles']} ({e['excluded_fraction']:.3%})"
                       if e["excluded_particles"] else "") + (
            f", left the tank {e['left_tank_particles']} ({e['left_tank_fraction']:.3%})"
            if e["left_tank_particles"] else "")

    def __call__(self, run):
        t, end = min(run.solver.time, run.output.end_time), run.output.end_time
        if self.tty:
            self.bar.n = t
            self.bar.set_postfix_str(self.postfix(run), refresh=True)
            if run.done:
                self.bar.close()
        elif run.done or run.next_output % self.every == 0:
            line = self.bar.format_meter(t, end, time.perf_counter() - self.start, ncols=100,
                                         bar_format=self.FORMAT, postfix=self.postfix(run), ascii=True)
            self.stream.write(line + "\n")
            self.stream.flush()


def _at_least_one(text: str) -> int:
    """An argparse type: a whole number >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not allowed; expected a whole number >= 1")
    return value


def run_main(argv=None):
    parser = argparse.ArgumentParser(prog="gpusph-run", description="Run a scene headless and record it to MCAP.")
    parser.add_argument("scene", nargs="?", help="built-in scene name or path to a scene YAML file")
    parser.add_argument("--run-config", action="append", default=[], metavar="NAME|FILE",
                        help="run configuration(s), later ones winning (e.g. thesis_scenario1)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override one run setting")
    parser.add_argument("--out", help="bag directory to create (must not exist or be empty)")
    parser.add_argument("--resume", metavar="DIR", help="continue the run recorded in DIR from its last checkpoint "
                        "(written every checkpoint_interval of wall time and when the run is stopped)")
    parser.add_argument("--quiet", action="store_true", help="no progress output")
    args = parser.parse_args(argv)
    new_run = args.scene is not None or args.out is not None or args.set or args.run_config
    if (args.resume is not None) == bool(new_run):
        parser.error("give a scene and --out (and settings), or --resume DIR alone (it runs as the run it continues "
                     "was invoked)")
    if args.resume is None and (args.scene is None or args.out is None):
        parser.error("a new run needs a scene and --out")

    import warp as wp

    wp.config.log_level = wp.LOG_WARNING  # no per-module load lines
    # SIGTERM and Ctrl-C only ask the run to stop between two steps (a second Ctrl-C stops it at
    # once): an exception raised wherever the signal lands (inside the MCAP writer, say) could leave
    # the recording unclosable and the state half-stepped. Set before anything is built (a stop
    # asked for while the run builds ends it at its first step, with a checkpoint), and put back
    # after (a caller's own handlers, a test runner's, are its business again)
    stop = threading.Event()

    def ask_to_stop(signum, frame):
        if signum == signal.SIGINT and stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    previous = {sig: signal.signal(sig, ask_to_stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        from .sph import ConfigError
        from .sph.exchange import world

        try:
            comm = world()
        except ConfigError as err:
            print(f"gpusph-run: {err}", file=sys.stderr)
            return 1
        if comm is None:
            return _run(args, stop)
        try:  # a rank that raises takes the others down with it, where they would wait for it forever
            return _run(args, stop, comm)
        except BaseException:
            import traceback

            traceback.print_exc()
            sys.stderr.flush()
            comm.Abort(1)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _run(args, stop, comm=None) -> int:
    """gpusph-run's work, once its arguments are checked; ``stop`` is set by SIGTERM or Ctrl-C.
    ``comm``: the MPI ranks it runs on (mpiexec -n N, N > 1; sph/exchange.py): every rank steps,
    rank 0 alone writes and speaks, and a run on ranks resumes on any number of ranks (sph/portable.py)."""
    from pathlib import Path

    from .analysis import report as R
    from .output.folders import folder_problem
    from .runner import Checkpoints, Run, resume
    from .scenes.schema import load_scene
    from .scenes.settings import resolve
    from .sph import ConfigError

    root = comm is None or comm.rank == 0
    out = args.out if args.resume is None else args.resume
    problem = None if args.resume is not None or not root else folder_problem(args.out, empty=True)
    if comm is not None:
        problem = comm.bcast(problem)
    if problem:
        if root:
            print(f"gpusph-run: --out: {args.out!r} cannot be written: {problem}", file=sys.stderr)
        return 1
    recorder, failed = None, None
    try:
        if args.resume is not None:
            run, recorder, invocation = resume(args.resume, comm)
        else:
            # files by absolute path: a resume may start from another folder
            def where(name):
                return str(Path(name).resolve()) if Path(name).is_file() else name

            invocation = {"scene": where(args.scene), "run_config": [where(f) for f in args.run_config],
                          "sets": args.set}
            scene = load_scene(args.scene)
            run = Run(scene, resolve(scene, files=args.run_config, sets=args.set), comm=comm)
            if root:
                recorder = run.open_recording(args.out)
    except (ConfigError, FileExistsError, ValueError, OSError) as err:
        failed = f"gpusph-run: {err}"
    if comm is not None:  # one rank's failure is every rank's (the recording is rank 0's alone)
        failed = next((f for f in comm.allgather(failed) if f), None)
    if failed:
        if root:
            print(failed, file=sys.stderr)
        return 1
    say = print if root else (lambda *a, **k: None)  # rank 0 speaks for the run
    for warning in run.scene.warnings:
        say(f"gpusph-run: warning: {warning}", file=sys.stderr)
    resumed = f" (resumed at t = {run.solver.time:.4g} s)" if args.resume is not None else ""
    say(f"{run.summary()} -> {out}{resumed}", flush=True)
    every = run.output.checkpoint_interval
    checkpoints = Checkpoints(out, invocation, recorder, every, comm)
    start = time.perf_counter()
    result = run.execute(recorder, progress=None if args.quiet or not root else Progress(run), stop=stop.is_set,
                         checkpoints=checkpoints if every else None)
    say(f"{result['status']}: {result['steps']} steps, t = {result['simulated_time_s']:.4g} s, wall "
        f"{time.perf_counter() - start:.1f} s, {result['mipps']} MIPPS; {R.excluded_line(result)}; recorded "
        f"{recorder.count if root else 0} messages to {out}", flush=True)
    if result["status"] == "completed" and root:
        checkpoints.remove()
    elif result["status"] == "interrupted" and every and not run.torn:
        try:
            written = checkpoints.write(run)
            say(f"checkpoint: {written}; continue with gpusph-run --resume {out}", flush=True)
        except (OSError, ValueError) as err:  # a full disk, a path that is no regular file: said, not a traceback
            say(f"gpusph-run: no checkpoint written: {err}", file=sys.stderr, flush=True)
    return 0 if result["status"] == "completed" else 2


def analyze_main(argv=None):
    parser = argparse.ArgumentParser(prog="gpusph-analyze",
                                     description="The thesis's metrics of a recording beside the experiment "
                                                 "and GPUSPH.")
    parser.add_argument("recording", help="bag directory written by gpusph-run or sim_node")
    parser.add_argument("--charts", help="where metrics.json and the PNG charts go (default: DIR/analysis)")
    parser.add_argument("--reference", help="a reference folder laid out as the package's data/ "
                                            "(default: the package's own)")
    parser.add_argument("--no-charts", action="store_true")
    parser.add_argument("--export", metavar="DIR",
                        help="write the simulated and measured series on the recording's clock as CSV, and the "
                             "measured ones as a bag of /reference/... topics, into DIR; then stop")
    parser.add_argument("--repair", action="store_true",
                        help="rebuild a killed recording's index (summary, footer, metadata.yaml) from its complete "
                             "chunks, so rosbags and mcap open it; then stop")
    args = parser.parse_args(argv)
    from pathlib import Path

    if args.repair:
        return _repair(args.recording)
    from .analysis import report as R

    if args.export:
        return _export(args.recording, args.export, args.reference)
    if (Path(args.recording) / "results.csv").is_file():
        return _analyze_study(Path(args.recording))
    recording = Path(args.recording)
    try:
        rep, curves = R.analyse(recording, Path(args.reference) if args.reference else None)
    except (OSError, KeyError, ValueError) as err:
        print(f"gpusph-analyze: {err}", file=sys.stderr)
        return 1
    print(R.table(rep))
    out = Path(args.charts) if args.charts else (recording if recording.is_dir() else recording.parent) / "analysis"
    try:
        path = R.write(rep, out)
        written = [] if args.no_charts else R.charts(rep, curves, out)
    except OSError as err:
        print(f"gpusph-analyze: --charts: {out} cannot be written: {err.strerror or err}", file=sys.stderr)
        return 1
    print(f"\nmetrics: {path}" + ("".join(f"\nchart: {w}" for w in written)))
    if not rep["complete"]:
        print("note: the recording ends mid-file (a killed run); metrics cover what it holds")
    return 0


def _export(recording, out, reference) -> int:
    from pathlib import Path

    from .analysis.export import export

    try:
        done = export(recording, out, Path(reference) if reference else None)
    except (OSError, KeyError, ValueError) as err:
        print(f"gpusph-analyze: --export: {err}", file=sys.stderr)
        return 1
    for path in done["csv"]:
        print(f"csv: {path}")
    print(f"reference bag: {done['bag']} (" + ", ".join(f"{t} {n}" for t, n in done["topics"].items()) + ")")
    return 0


def _repair(bag) -> int:
    from .output.recording import repair

    try:
        found = repair(bag)
    except (OSError, ValueError) as err:
        print(f"gpusph-analyze: {err}", file=sys.stderr)
        return 1
    if not found["repaired"]:
        print(f"{found['file']} is whole: nothing to repair")
        return 0
    if found["problem"]:
        print(f"{found['file']} ends whole but cannot be read: {found['problem']}")
    print(f"repaired {found['file']}: {found['messages']} messages on {len(found['topics'])} topics recovered "
          f"from its complete chunks (the cut file is kept as {found['cut_file']})")
    return 0


def _analyze_study(folder) -> int:
    import json

    from .analysis.reference import data_dir
    from .study import charts, table

    rows = table.read(folder / "results.csv")
    metrics = json.loads((folder / "study.json").read_text())["metrics"]
    print(table.thesis_tables(rows, metrics))
    print("\n" + table.headline(rows, metrics))
    (folder / "results.md").write_text(table.markdown(rows, metrics))
    written = [folder / "results.md"] + charts.write(rows, metrics, folder / "charts", data_dir())
    print("".join(f"\nchart: {w}" for w in written))
    return 0


def sweep_main(argv=None):
    parser = argparse.ArgumentParser(prog="gpusph-sweep",
                                     description="Run a study's cases on Dask, tabulate and chart them.")
    parser.add_argument("study", help="a study in config/studies or a path to a study YAML file")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    parser.add_argument("--out", help="results folder (default: the study's `out`)")
    args = parser.parse_args(argv)
    import json

    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from .analysis.reference import data_dir
    from .sph import ConfigError
    from .study import charts, table
    from .study.schema import load_study, with_out
    from .study.sweep import sweep

    try:
        study = load_study(args.study)
    except ConfigError as err:
        print(f"gpusph-sweep: {err}", file=sys.stderr)
        return 1
    if args.out:
        study = with_out(study, args.out)
    try:
        study.out.mkdir(parents=True, exist_ok=True)
        (study.out / "study.json").write_text(json.dumps({"name": study.name, "metrics": study.metrics,
                                                          "cases": [c.name for c in study.cases()]}, indent=1))
    except OSError as err:
        print(f"gpusph-sweep: --out: {study.out} cannot be written: {err.strerror or err}", file=sys.stderr)
        return 1
    try:
        rows = sweep(study, scheduler=args.scheduler, progress=lambda line: print(line, flush=True))
    except (OSError, ValueError, TimeoutError) as err:  # a scheduler address that is none, or none answers
        print(f"gpusph-sweep: --scheduler: {args.scheduler!r}: {err}" if args.scheduler else f"gpusph-sweep: {err}",
              file=sys.stderr)
        return 1
    (study.out / "results.md").write_text(table.markdown(rows, study.metrics))
    written = table.write(rows, study.out) + [study.out / "results.md"] + charts.write(
        rows, study.metrics, study.out / "charts", data_dir())
    print(table.thesis_tables(rows, study.metrics))
    print("\n" + table.headline(rows, study.metrics))
    print("".join(f"\nwrote {w}" for w in written))
    return 0


def plan_main(argv=None):
    parser = argparse.ArgumentParser(prog="gpusph-plan", description="Particles, device memory, steps and wall time "
                                     "of a run, from a short calibration run on its device.")
    parser.add_argument("scene", help="built-in scene name or path to a scene YAML file")
    parser.add_argument("--run-config", action="append", default=[], metavar="NAME|FILE")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--calibration-steps", type=_at_least_one, default=30,
                        help="steps timed on the device to estimate the step rate (>= 1)")
    parser.add_argument("--no-reductions", action="store_true",
                        help="price only the run as configured, not each scene reduction that applies")
    parser.add_argument("--estimate", action="store_true",
                        help="price the run from the scene alone, nothing built or run: particles, memory on "
                             "its device and whether it is free there, the fewest steps (for runs larger than "
                             "this machine, or for a device it does not have)")
    parser.add_argument("--ranks", type=_at_least_one, default=None, metavar="N",
                        help="the run cut for N MPI ranks instead: slabs of whole cells along the longest axis, "
                             "each rank's particles, halo, memory and halo exchange a step (nothing timed); "
                             "refused where a rank would be fewer than 3 cells across")
    args = parser.parse_args(argv)
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING
    from . import plan as pricing
    from .plan import coarse_plan, estimate, estimate_text, is_large, plan, plan_reductions, table, text
    from .scenes.schema import load_scene
    from .scenes.settings import resolve
    from .sph import ConfigError

    try:
        scene = load_scene(args.scene)
        config = resolve(scene, files=args.run_config, sets=args.set)
        if args.ranks:
            print(pricing.rank_text(pricing.rank_plan(scene, config, args.ranks)))
            return 0
        if args.estimate:
            print(estimate_text(estimate(scene, config)))
            return 0
        if is_large(scene, config):
            e = coarse_plan(scene, config, args.calibration_steps)
            print(estimate_text(e))
            if e["fits"] is False:
                print(f"gpusph-plan: dx = {e['dx']:g} m needs up to {e['particles']:.3g} particles, "
                      f"{e['device_bytes'] / 2 ** 30:.3g} GiB on {e['device']}: {e['limit']}", file=sys.stderr)
                return 1
            return 0
        if args.no_reductions:
            print(text(plan(scene, config, args.calibration_steps)))
            return 0
        plans, skipped = plan_reductions(scene, config, args.calibration_steps)
    except (ConfigError, ValueError) as err:  # a run the machine cannot hold is refused before calibrating
        print(f"gpusph-plan: {err}", file=sys.stderr)
        return 1
    print(text(plans[0]))
    print("\nthe same run under each reduction of the scene (cost: estimated wall time, share of the first):")
    print(table(plans, skipped))
    return 0


def stability_main(argv=None):
    from .study import stability as st

    parser = argparse.ArgumentParser(prog="gpusph-stability", description="Largest stable CFL and smallest stable "
                                     "sound speed of each kernel x viscosity x boundary x density treatment x "
                                     "shifting x XSPH on a small dam break, and how each failure showed itself.")
    parser.add_argument("--out", default="runs/stability", help="folder for stability.csv, .md and the map")
    parser.add_argument("--scene", default="collapse_2d")
    parser.add_argument("--dx", type=float, default=0.05715 / 10)
    parser.add_argument("--end-time", type=float, default=0.3)
    parser.add_argument("--iterations", type=int, default=4, help="bisection steps past the two ends")
    parser.add_argument("--workers", type=int, default=2, help="runs side by side (processes)")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--report", action="store_true", help="only redraw the table and map from stability.csv")
    for name, choices in (("kernels", st.KERNELS), ("viscosities", st.VISCOSITIES), ("boundaries", st.BOUNDARIES),
                          ("densities", st.DENSITIES), ("shifting", st.SWITCHES), ("xsph", st.SWITCHES)):
        parser.add_argument(f"--{name}", nargs="+", choices=choices, default=list(choices))
    args = parser.parse_args(argv)
    if args.report:
        print("\n".join(f"wrote {p}" for p in st.report(args.out)))
        return 0
    combos = st.combinations(args.kernels, args.viscosities, args.boundaries, args.densities, args.shifting, args.xsph)
    print(f"gpusph-stability: {len(combos)} combinations of {args.scene} at dx = {args.dx:g} m to t = "
          f"{args.end_time:g} s on {args.device}, {args.workers} at a time", flush=True)
    st.run_study(args.out, args.scene, args.end_time, args.dx, args.iterations, args.workers, combos, args.device,
                 progress=lambda line: print(line, flush=True))
    print(f"wrote {args.out}/stability.csv, stability.md, stability_map.png")
    return 0


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    commands = {"run": run_main, "analyze": analyze_main, "sweep": sweep_main, "plan": plan_main,
                "stability": stability_main}
    if not argv or argv[0] not in commands:
        print("usage: python -m gpusph_ros.cli {run,analyze,sweep,plan,stability} ...", file=sys.stderr)
        return 1
    return commands[argv[0]](argv[1:])


if __name__ == "__main__":
    sys.exit(main())
