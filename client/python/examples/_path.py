"""Lets the examples run from a source checkout: when ``import modskill`` fails (the package is
not installed), they import it from ``<repo>/client/python``, which holds the generated protocol
modules too (``modskill/v1``, committed)."""

import importlib
import os
import sys


def ensure_modskill_importable() -> None:
    try:
        importlib.import_module("modskill")
        return
    except ImportError:
        pass
    package_dir = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
    if os.path.isfile(os.path.join(package_dir, "modskill", "v1", "modskill_pb2_grpc.py")):
        sys.path.insert(0, package_dir)
        return
    sys.exit("cannot import modskill: pip install ./client/python (see client/python/README.md)")
