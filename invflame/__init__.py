"""invflame: hyperspectral infrared flame-emission tomography.

The flame domain on top of the domain-agnostic :mod:`operators` and :mod:`solvers`
packages: spectroscopy, geometry, ground-truth fields, representations, experiments and
the command-line interface.
"""

__version__ = "0.1.0"
