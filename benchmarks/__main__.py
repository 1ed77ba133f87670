"""Run the benchmarks and print the results: ``python -m benchmarks [--markdown [FILE]] [solver]
[scattered] [csv] [rig-read] [predict] [force] [likelihood] [creep-laws] [engine] [map-search]
[long-run] [fit] [rig-fit] [evidence] [evidence-seeds] [compare] [dynesty] [hierarchical]
[population-sizes] [transport-map] [diagnose] [demo]``.

``--markdown`` also writes each benchmark's result as a row of the current table of FILE
(default BENCHMARKS.md, the table ``benchmarks``; :mod:`validation.tables`): the rows of the
benchmarks run are replaced, each with its date, commit and machine; the others are kept.

Each run first prints the machine and its speed on fixed reference loads (``benchmarks.machine``),
so numbers from different days can be read against their machine. Without names all run but
``dynesty`` (an optional cross-check, 30–40 min on 2 cores; needs ``pip install dynesty``),
``evidence-seeds`` and ``compare`` (the default compare path against the ladder, ~15 min); ``fit``
(converged Burgers fits of one specimen, five seeds, in both coordinates), ``rig-fit`` (the divider
rig in both coordinates), ``evidence``, ``hierarchical``, ``population-sizes`` (3, 6, 16 specimens'
hyper-posteriors in both coordinates), ``map-search`` (the MAP search's wall time on three
posteriors), ``diagnose``, ``demo`` and ``force`` (a calibration fit
before the timed reading) take minutes.
"""

import os
import sys

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")


from benchmarks import (  # noqa: E402
    compare_default,
    creep_laws,
    csv_read,
    demo,
    diagnose,
    dynesty_check,
    engine,
    evidence,
    fit,
    force,
    hierarchical,
    likelihood,
    long_run,
    machine,
    map_search,
    population_sizes,
    predict,
    rig_fit,
    rig_read,
    scattered,
    solver,
    transport_map,
)  # noqa: E402
from fsrbayes.data.sensors import load_sensor  # noqa: E402
from validation.tables import markdown_option, measured_on, write_rows  # noqa: E402

TABLE_HEADER = ("benchmark", "result", "measured", "commit", "machine")

BENCHMARKS = {
    "solver": lambda: solver.report(solver.run(dict(load_sensor("a201").params))),
    "scattered": lambda: scattered.report(scattered.run()),
    "csv": lambda: csv_read.report(csv_read.run()),
    "rig-read": lambda: rig_read.report(rig_read.run()),
    "predict": lambda: predict.report(predict.run()),
    "force": lambda: force.report(force.run()),
    "likelihood": lambda: "\n".join(
        [likelihood.report(likelihood.run()), likelihood.report_rig(likelihood.run_rig())]
    ),
    "creep-laws": lambda: creep_laws.report(creep_laws.run()),
    "engine": lambda: engine.report(engine.run()),
    "map-search": lambda: map_search.report(map_search.run()),
    "long-run": lambda: "\n".join(
        [long_run.report(long_run.run()), long_run.report(long_run.run(check_growth=0.0))]
    ),
    "fit": lambda: fit.report_seeds(fit.run_seeds()),
    "rig-fit": lambda: rig_fit.report(rig_fit.run()),
    "evidence": lambda: evidence.report(evidence.run()),
    "compare": lambda: compare_default.report(compare_default.run()),
    "evidence-seeds": lambda: evidence.report_seeds(evidence.run_seeds()),
    "dynesty": lambda: dynesty_check.report(dynesty_check.run()),
    "hierarchical": lambda: hierarchical.report(hierarchical.run()),
    "population-sizes": lambda: population_sizes.report(population_sizes.run()),
    "transport-map": lambda: transport_map.report(transport_map.run()),
    "diagnose": lambda: diagnose.report(diagnose.run()),
    "demo": lambda: demo.report(demo.run()),
}


def main(argv):
    markdown, argv = markdown_option(argv, "BENCHMARKS.md")
    names = argv
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        print(f"unknown benchmark(s) {unknown}; choose from {list(BENCHMARKS)}", file=sys.stderr)
        return 2
    box = machine.run()
    print(machine.report(box), flush=True)
    rows = []
    for name in names or [
        n for n in BENCHMARKS if n not in ("dynesty", "evidence-seeds", "compare")
    ]:
        result = BENCHMARKS[name]()
        print(result, flush=True)
        rows.append([name, result, *measured_on(box["cpu"], box["cores"])])
    if markdown:
        write_rows(markdown, "benchmarks", TABLE_HEADER, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
