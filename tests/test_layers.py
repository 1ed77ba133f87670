"""Imports flow upwards only: the physics layer stays free of samplers and plotting."""

import subprocess
import sys


def test_physics_does_not_import_emcee_arviz_or_matplotlib():
    code = ("import sys, fsrbayes.physics, fsrbayes; "
            "bad = sorted(m for m in ('emcee', 'arviz', 'matplotlib', 'corner') if m in sys.modules); "
            "print(','.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_physics_imports_nothing_from_the_layers_above():
    code = ("import sys, fsrbayes.physics; "
            "print(','.join(sorted(m for m in sys.modules if m.startswith('fsrbayes.') "
            "and not m.startswith('fsrbayes.physics'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    # Importing the subpackage runs fsrbayes/__init__, which pulls data.sensors; nothing else.
    assert set(filter(None, out.stdout.strip().split(","))) <= {"fsrbayes.data", "fsrbayes.data.sensors",
                                                               "fsrbayes.data.distributions"}
