"""Wall time of ``fsrbayes demo``: the full plan (target <= 15 minutes) and ``--quick`` (<= 1
minute).

Both run on the shipped data with 2 worker processes into temporary folders; the
stages' times come from the demo's own progress lines.
"""

import tempfile
import time

from fsrbayes.demo import QUICK, run_demo
from fsrbayes.demo.plan import FULL


def _timed(plan):
    lines = []
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        results = run_demo(out, plan, processes=2, echo=lines.append)
        seconds = time.perf_counter() - start
    stages = [
        line for line in lines if not line.lstrip("[ 0123456789s]").startswith(("a201-", "fsr402-"))
    ]
    return {
        "plan": plan.name,
        "seconds": seconds,
        "n_specimens": results["n_specimens"],
        "n_tests": results["n_tests"],
        "stages": stages,
        "warnings": len(results["warnings"]),
    }


def run():
    return [_timed(QUICK), _timed(FULL)]


def report(runs):
    out = []
    for r in runs:
        target = 60 if r["plan"] == "quick" else 900
        out.append(
            f"demo ({r['plan']}): {r['seconds']:.0f} s (target <= {target} s), {r['n_specimens']} "
            f"specimens, {r['n_tests']} creep tests, {r['warnings']} warnings"
        )
        out += [f"    {line}" for line in r["stages"]]
    return "\n".join(out)
