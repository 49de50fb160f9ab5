"""The runs a scripts/bench_*.sh made through bench_lib.sh's bench_run, for its report step:

    import sys; sys.path.insert(0, "scripts"); from bench_runs import runs
    for name, mode, report in runs(out): ...

yields (input name, mode, report.json as a dict) for each OUT/runs/INPUT__MODE/report.json in name order; a run
that failed (no report.json) is left out, its log says why."""
import json
import os


def runs(out):
    base = os.path.join(out, "runs")
    for d in sorted(os.listdir(base)):
        path = os.path.join(base, d, "report.json")
        if not os.path.isfile(path):
            continue
        name, mode = d.rsplit("__", 1)
        with open(path) as f:
            yield name, mode, json.load(f)
