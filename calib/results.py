"""What every result object of tiltbench shares: value equality, hashing, notebook rendering.

Result objects are frozen dataclasses holding numpy arrays (statsmodels-like; docs/conventions.md).
The dataclass-generated ``==`` compares tuples of fields, which raises on arrays
(``ValueError: truth value of an array is ambiguous``). :class:`ResultMixin` replaces it with a
field-by-field comparison (:func:`same`): arrays by shape and value (``NaN`` equal to ``NaN``),
dicts by keys and values, lists and tuples element by element, nested results by their own
``==``. Fields declared with ``field(compare=False)`` are ignored, as dataclasses do.

Serialisation contract (checked by ``tests/test_api.py``)::

    T.from_dict(x.to_state()) == x            # every result type, also through JSON
    T.from_dict(x.to_dict())  == x            # where to_dict() carries everything
    T.from_dict(x.to_dict()).to_dict() == x.to_dict()   # the printed document, always

``to_dict()`` is the documented object the commands print (``--json``); its keys and values
are frozen by ``tests/test_snapshot.py``. Where it leaves out something a rebuild needs (e.g.
residuals), ``to_state()`` returns ``to_dict()`` plus the missing keys — a superset, so
``from_dict`` reads both. By default ``to_state()`` is ``to_dict()``.

A class using the mixin is declared ``@dataclass(frozen=True, eq=False)`` (``eq=False`` keeps
the dataclass machinery from overwriting ``__eq__``) and sets ``_TITLE`` and ``_UNITS`` for the
notebook rendering ``_repr_markdown_`` (the title, ``summary()`` verbatim, the units).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

__all__ = ["ResultMixin", "readonly", "same"]


def _unwritable(a: np.ndarray) -> bool:
    """True when nothing can write ``a``'s data: it and every array it views are read-only,
    down to an owner (a view of a writeable array, or of a buffer, may still change)."""
    while isinstance(a, np.ndarray):
        if a.flags.writeable:
            return False
        if a.base is None:
            return True
        a = a.base
    return False


def readonly(a: Any, dtype: Any = float) -> np.ndarray:
    """``a`` as a read-only array of ``dtype``: a copy, unless ``a`` already is one that
    nothing can write (:func:`_unwritable`) — then it is shared, not copied (a long log's arrays
    go through several frozen records: ``dataclasses.replace`` must not double its memory)."""
    if isinstance(a, np.ndarray) and a.dtype == np.dtype(dtype) and _unwritable(a):
        return a
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


def _is_num(x: Any) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)


def same(a: Any, b: Any) -> bool:
    """Value equality for result fields (module docstring): arrays, mappings, sequences."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.shape != b.shape:
            return False
        if a.dtype.kind in "fc" or b.dtype.kind in "fc":
            return bool(np.array_equal(a, b, equal_nan=True))
        return bool(np.array_equal(a, b))
    if isinstance(a, dict) or isinstance(b, dict):
        return (isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys()
                and all(same(a[k], b[k]) for k in a))
    if isinstance(a, (list, tuple)) or isinstance(b, (list, tuple)):
        # A tuple that went through JSON comes back as a list: same values, same result.
        return (isinstance(a, (list, tuple)) and isinstance(b, (list, tuple))
                and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True)))
    if _is_num(a) and _is_num(b):
        return bool(a == b or (math.isnan(a) and math.isnan(b)))
    return bool(a == b)


def _frozen(v: Any) -> Any:
    """A hashable key with ``same(a, b) ⇒ _frozen(a) == _frozen(b)``."""
    if isinstance(v, np.ndarray):
        return ("array", v.shape, tuple(_frozen(x) for x in v.ravel().tolist()))
    if isinstance(v, dict):
        return ("dict", frozenset((k, _frozen(x)) for k, x in v.items()))
    if isinstance(v, (list, tuple)):
        return ("seq", tuple(_frozen(x) for x in v))
    if _is_num(v):
        f = float(v)
        return "nan" if math.isnan(f) else f  # hash(nan) is per object since Python 3.10
    if isinstance(v, ResultMixin):
        return hash(v)
    return v


class ResultMixin:
    """Field-wise ``==``, a matching ``hash`` and ``_repr_markdown_`` for result dataclasses."""

    _TITLE: str = ""
    _UNITS: str = ""

    def _compared(self) -> tuple:
        return tuple(f.name for f in dataclasses.fields(self) if f.compare)  # type: ignore[arg-type]

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(same(getattr(self, n), getattr(other, n)) for n in self._compared())

    def __hash__(self) -> int:
        return hash((type(self).__name__,
                     tuple(_frozen(getattr(self, n)) for n in self._compared())))

    def to_state(self) -> dict:
        """Everything :meth:`from_dict` needs to rebuild this object exactly (JSON-ready)."""
        return self.to_dict()  # type: ignore[attr-defined]

    def _repr_markdown_(self) -> str:
        """Notebook rendering: title, :meth:`summary` and the units of the numbers."""
        title = self._TITLE or type(self).__name__
        body = self.summary()  # type: ignore[attr-defined]
        return f"**{title}**\n\n```text\n{body}\n```\n\nUnits: {self._UNITS}\n"
