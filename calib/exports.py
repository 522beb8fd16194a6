"""Lazy public exports of a package (PEP 562), one implementation for ``calib`` and ``bench``.

``import calib`` / ``import bench`` stay cheap (the command line starts without scipy, mujoco,
matplotlib or rerun): an exported name is imported on first use and then kept as a plain
attribute. ``dir(package)`` lists the exports.
"""

from __future__ import annotations

import sys
import types
from collections.abc import Callable, Mapping


class _Package(types.ModuleType):
    """Keeps an exported function when its same-named submodule is imported
    (``calib.calibration.correct``, ``bench.validate``): the import system would otherwise replace
    the attribute with the module."""

    def __setattr__(self, name: str, value) -> None:
        if (name in self.__dict__.get("_EXPORTS", ()) and isinstance(value, types.ModuleType)
                and value.__name__ == f"{self.__name__}.{name}"):
            return
        super().__setattr__(name, value)


def install_lazy_exports(package: str, exports: Mapping[str, str],
                         load: Callable[[str], types.ModuleType]) -> None:
    """Give ``package`` a module ``__getattr__`` / ``__dir__`` that resolve ``exports``.

    Parameters
    ----------
    package : the package's ``__name__``.
    exports : public name → ``"module:attribute"``.
    load : imports a module named in ``exports`` and returns it (plain ``import`` statements
        in the package, so the import-rule test sees every edge; no ``importlib``).
    """
    module = sys.modules[package]

    def module_getattr(name: str):
        target = exports.get(name)
        if target is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        mod, attr = target.split(":")
        value = getattr(load(mod), attr)
        setattr(module, name, value)  # once resolved, a plain attribute
        return value

    def module_dir() -> list[str]:
        return sorted(set(vars(module)) | set(exports))

    module._EXPORTS = dict(exports)
    module.__getattr__ = module_getattr
    module.__dir__ = module_dir
    module.__class__ = _Package
