"""Speed benchmarks of fsrbayes; run with ``python -m benchmarks`` (results in BENCHMARKS.md)."""
