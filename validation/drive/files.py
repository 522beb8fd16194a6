"""The files of one case, as a user would hand them to ``tiltbench gap``.

* ``mat`` — the course ``ensayo.mat`` (MATLAB v5, scipy.io): ``tita`` (N×1 rad), ``datos``
  (N×2 m/s², x first) and, when the timing is ``"t"``, ``t`` (N×1 s).
* ``csv_ms2`` / ``csv_counts`` — a measured log with a header: an optional time column (s), a
  θ column (rad, the encoder) and the two tilt-plane axes, in m/s² (6 decimals) or in raw
  integer counts (``round(y / 9.80665 · S)``, S counts per g). Two header styles: *named*
  (``t (s),theta (rad),ax (m/s^2),ay (m/s^2)``, units read from the header; counts say
  ``(counts)``) and *custom* (``time_s;enc_rad;acc_u;acc_v``, ``;``-separated, given with
  ``--columns`` and ``--units``). Counts always get ``--units counts --sensitivity S``.
* ``datos.txt`` (course wording) when the case states its noise that way (``--datos``).

:func:`plan` decides a case's file and the options of ``tiltbench gap`` (recorded in the
truth, used by the scorer); :func:`write` writes them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io

from .sensor import G_UNIT


def plan(fmt: str, timing: str, rate_hz: float, stated, stated_by: str, sens: float | None,
         rng: np.random.Generator) -> dict:
    """The file of a case and the ``tiltbench gap`` options it needs."""
    opts: dict = {"noise_var": None, "datos": None, "rate": None, "units": None,
                  "sensitivity": None, "columns": None}
    if stated_by == "datos":
        opts["datos"] = "datos.txt"
    else:
        opts["noise_var"] = [float(v) for v in stated]
    if timing == "rate":
        opts["rate"] = float(rate_hz)
    if fmt == "mat":
        info = {"name": "ensayo.mat", "format": "course",
                "variables": ["tita", "datos"] + (["t"] if timing == "t" else [])}
        return {"file": info, "options": opts}
    style = "named" if rng.uniform() < 0.5 else "custom"
    counts = fmt == "csv_counts"
    timed = timing == "t"
    if style == "named":
        unit = "counts" if counts else "m/s^2"
        cols = (["t (s)"] if timed else []) + ["theta (rad)", f"ax ({unit})", f"ay ({unit})"]
        delim = ","
    else:
        cols = (["time_s"] if timed else []) + ["enc_rad", "acc_u", "acc_v"]
        delim = ";"
        opts["columns"] = ",".join((["t=time_s"] if timed else [])
                                   + ["theta=enc_rad", "x=acc_u", "y=acc_v"])
        opts["units"] = "m/s2"
    if counts:
        opts["units"] = "counts"
        opts["sensitivity"] = float(sens)
    info = {"name": "log.csv", "format": "csv", "style": style, "delimiter": delim,
            "header": cols, "units": "counts" if counts else "m/s2",
            "sensitivity": float(sens) if counts else None,
            "count_step": G_UNIT / sens if counts else None}
    return {"file": info, "options": opts}


def gap_args(opts: dict, folder: Path | str = ".") -> list[str]:
    """The ``tiltbench gap`` arguments after the file (``folder``: where ``datos.txt`` is)."""
    args = []
    if opts.get("datos"):
        args += ["--datos", str(Path(folder) / opts["datos"])]
    else:
        args += ["--noise-var", ",".join(repr(float(v)) for v in opts["noise_var"])]
    if opts.get("rate"):
        args += ["--rate", repr(float(opts["rate"]))]
    if opts.get("columns"):
        args += ["--columns", opts["columns"]]
    if opts.get("units"):
        args += ["--units", opts["units"]]
    if opts.get("sensitivity"):
        args += ["--sensitivity", repr(float(opts["sensitivity"]))]
    return args


def datos_text(noise_var) -> str:
    """``datos.txt`` in the course's wording (only the variances matter to ``gap``)."""
    pair = " ".join(repr(float(v)) for v in noise_var)
    return ("Posición inicial = [0 0]\nVelocidad inicial = [0 0]\n"
            f"varianza del ruido de los acelerómetros = [{pair}]")


def write(folder: Path, fp: dict, theta: np.ndarray, time: np.ndarray, datos: np.ndarray,
          timing: str, stated) -> None:
    """Write the case's file (and ``datos.txt``) into ``folder`` (which must exist)."""
    info, opts = fp["file"], fp["options"]
    if opts.get("datos"):
        (folder / opts["datos"]).write_text(datos_text(stated), encoding="utf-8")
    if info["format"] == "course":
        mat = {"tita": theta.reshape(-1, 1), "datos": np.asarray(datos, dtype=float)}
        if timing == "t":
            mat["t"] = time.reshape(-1, 1)
        scipy.io.savemat(folder / info["name"], mat, format="5", do_compression=False)
        return
    cols, fmts = [], []
    if timing == "t":
        cols.append(time)
        fmts.append("%.6f")
    cols.append(theta)
    fmts.append("%.10f")
    if info["units"] == "counts":
        counts = np.round(np.asarray(datos) / G_UNIT * info["sensitivity"])
        cols += [counts[:, 0], counts[:, 1]]
        fmts += ["%d", "%d"]
    else:
        cols += [datos[:, 0], datos[:, 1]]
        fmts += ["%.6f", "%.6f"]
    np.savetxt(folder / info["name"], np.column_stack(cols), fmt=fmts,
               delimiter=info["delimiter"], header=info["delimiter"].join(info["header"]),
               comments="")


__all__ = ["datos_text", "gap_args", "plan", "write"]
