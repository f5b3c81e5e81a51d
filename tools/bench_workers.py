"""The error-run stage of a profile on 1, 2, ... Dask workers, side by side in one run.

The error runs of the costliest nodes (training order) at every training period, over the first
``--frames`` frames inside an error window of ``--window`` of the frame (placed as the profiler
places it), are made three ways: in this process (the reference numbers), then on a
``LocalCluster`` of each worker count in ``--workers``. Each cluster is started before its clock
starts; its workers receive the scene once, render their reference frames once and compile each
variant they are given, all inside the timed stage, as in a profile. The numbers of every run are
compared with the in-process ones; the JSON written gives the wall time of each stage and the
ratios of the medians (``--workers 1,2,1,2`` interleaves repeats, so that load drifting over the
run touches both counts alike).

    nice -n 5 flock /tmp/measure.lock python tools/bench_workers.py shaders/marble.glsl \\
        sessions/marble.json --nodes 6 --frames 32 --workers 1,2 --out bench_workers.json

The runs are the training's own error runs (:func:`rrcache.harness.execute.execute` of a
:class:`rrcache.runs.RunSpec`); the cluster side is :mod:`rrcache.cluster`.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import time


class ErrorStage:
    """A context for :class:`rrcache.cluster.executor.DaskRuns`: ``run((node, period))`` is one
    error run; the scene is loaded, the references rendered and each node's variant compiled
    once per process."""

    def __init__(self, shader, session, frames, window, periods):
        self.shader, self.session_path = str(shader), str(session)
        self.frames, self.window, self.periods = int(frames), window, tuple(periods)
        self._bench = None

    def __getstate__(self):
        return {k: v for k, v in self.__dict__.items() if k != "_bench"}

    def __setstate__(self, state):
        self.__dict__.update(state, _bench=None)

    def run(self, spec):
        from rrcache.harness.execute import execute
        from rrcache.pipeline import WorkSource, load_bench
        from rrcache.runs import RunSpec
        from rrcache.runtime.spec import VariantSpec

        if self._bench is None:
            self._bench = load_bench(WorkSource(self.shader, self.session_path))
        node, period = spec
        size = tuple(int(v) for v in self._bench.session.resolution)
        result = execute(RunSpec("error", VariantSpec("cache", (node,), "three-pass", periods=(period,)),
                                 tuple(range(self.frames)), size, self.window), self._bench)
        return [result.steady_error, result.steady_psnr, result.hit_rate] + [f.error for f in result.frames]

    def release(self):
        if self._bench is not None:
            self._bench.close()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("shader")
    ap.add_argument("session")
    ap.add_argument("--nodes", type=int, default=6)
    ap.add_argument("--frames", type=int, default=32)
    ap.add_argument("--window", type=float, default=0.25)
    ap.add_argument("--periods", default="2,10,18,26,34,42,50")
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--out", default="bench_workers.json")
    args = ap.parse_args()

    from rrcache.cluster.client import connect
    from rrcache.cluster.executor import DaskRuns
    from rrcache.harness.renderer import Renderer
    from rrcache.pipeline import load_for_session
    from rrcache.profiler.plan import coverage_map, place_window
    from rrcache.profiler.train import training_order
    from rrcache.profiles.settings import TrainingSettings
    from rrcache.session import load_session

    session = load_session(args.session)
    work = load_for_session(args.shader, session)
    size = tuple(int(v) for v in session.resolution)
    window = place_window(coverage_map(work.prepared, session, range(0, args.frames, 4), Renderer), size, args.window)
    nodes = [n.id for n in training_order(work, session, TrainingSettings().resolved(session)).nodes[:args.nodes]]
    periods = [int(p) for p in args.periods.split(",")]
    specs = [(n, p) for n in nodes for p in periods]
    stage = ErrorStage(os.path.abspath(args.shader), os.path.abspath(args.session), args.frames, window, periods)

    t0 = time.perf_counter()
    reference = {spec: stage.run(spec) for spec in specs}
    stage.release()
    out = {"shader": args.shader, "session": args.session, "nodes": nodes, "periods": periods,
           "frames": args.frames, "window": list(window) if window else None, "runs": len(specs),
           "in_process_s": time.perf_counter() - t0, "load_before": os.getloadavg(), "workers": {}}
    for count in [int(w) for w in args.workers.split(",")]:  # "1,2,1,2": interleaved repeats
        with connect(workers=count, dashboard_address=":0", announce=print) as cluster:
            runs = DaskRuns(cluster)
            t0 = time.perf_counter()
            name = runs.open("bench", stage)
            got = dict(runs.map(name, [(spec, "error") for spec in specs]))
            wall = time.perf_counter() - t0
            runs.close()
        worst = max(max(abs(a - b) for a, b in zip(reference[s], got[s].result)) for s in specs)
        out["workers"].setdefault(str(count), []).append(
            {"wall_s": wall, "max_abs_difference": worst, "per_worker_runs": _count(runs.placements),
             "load": os.getloadavg()})
        print(f"{count} worker(s): {wall:.1f} s, largest difference from in-process {worst:.3g}", flush=True)
    median = {k: statistics.median(r["wall_s"] for r in v) for k, v in out["workers"].items()}
    if "1" in median:
        out["speedup_vs_1"] = {k: median["1"] / v for k, v in median.items()}
    out["load_after"] = os.getloadavg()
    with open(args.out, "w") as f:
        json.dump(out, f, indent=1)
    print(json.dumps({k: v for k, v in out.items() if k in ("in_process_s", "speedup_vs_1", "load_before",
                                                            "load_after")}))


def _count(placements) -> dict:
    out = {}
    for p in placements:
        out[p.worker] = out.get(p.worker, 0) + 1
    return out


if __name__ == "__main__":
    main()
