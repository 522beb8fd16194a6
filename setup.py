"""The package list for setuptools; everything else is in pyproject.toml.

Packages are discovered, with explicit includes: ``bench*`` and ``calib*`` (so ``validation/``,
``tests/``, ``tools/``, ``benchmarks/`` and a stray ``build/`` never ship), plus the three
folders that ship inside ``bench`` under other names: ``models/``, ``data/`` and ``docs/``
become ``bench.models``, ``bench.data`` and ``bench.docs`` (pyproject's ``package-dir``). This
is here, not in ``[tool.setuptools.packages.find]``, because that table does not read
``package-dir`` (pypa/setuptools#5145) and excludes a ``packages`` list beside it.
"""

from setuptools import find_packages, setup

SHIPPED = ["bench.models", "bench.data", "bench.docs"]

setup(packages=find_packages(include=["bench", "bench.*", "calib", "calib.*"]) + SHIPPED)
