"""catgraph: mapping in environments whose appearance changes.

Robust pose-graph optimisation (switchable constraints and their peers, on
Ceres), CAT-Graph+ loop closures, evaluation against ground truth and the
simulators, from Python. Poses and matrices are numpy arrays; docs/python.md
lists everything here.
"""
from ._catgraph import *  # noqa: F401,F403
from ._catgraph import FileError, __doc__ as _module_doc  # noqa: F401

__version__ = "@PROJECT_VERSION@"
