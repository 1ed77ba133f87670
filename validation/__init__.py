"""Validation studies of fsrbayes: closed-form test problems, calibration and recovery studies.

Not part of the installed package: these are what the tests and VALIDATION.md run to show that
the samplers, the evidence and the discrepancy workflow give the right answers on problems with
known ones. Run a study from the repository's root, e.g. ``python -m validation.recovery 20``.
"""
