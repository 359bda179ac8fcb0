"""Lets the examples run from a source checkout: when ``import modskill`` fails, they look for
the built package in ``<repo>/build/python`` (made by ``make modskill_python``)."""

import importlib
import os
import sys


def ensure_modskill_importable() -> None:
    try:
        importlib.import_module("modskill")
        return
    except ImportError:
        pass
    repo = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
    candidate = os.path.join(repo, "build", "python")
    if os.path.isdir(os.path.join(candidate, "modskill", "v1")):
        sys.path.insert(0, candidate)
        return
    sys.exit("cannot import modskill: build it (make modskill_python) and set PYTHONPATH=<build>/python")
