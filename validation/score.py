"""Score the gap analysis on the validation set: ``python -m validation.score``.

The only module of :mod:`validation` that imports ``calib``: it runs the analysis on each
case (default :func:`calib.gap.analyze_gap` with the case's stated ``noise_var``) and checks
its answer against the truth.

Rules
-----
* **catalog** case right ⇔ the set of named (name, axis) equals the expected set and the
  verdict is ``"explained"``. An expected effect also counts as found when the analysis lists
  it in a ``not_identifiable`` entry together with a named effect on a matching axis (equal,
  or one of them ``"both"``): that named effect then stands for it (the ties of
  ``docs/effects.md``: tilt_offset vs misalignment on both axes, lowpass_lag vs a tilt /
  misalignment at a constant rate, drift vs random walk).
* **clean** case right ⇔ nothing named and verdict ``"nothing_detected"``.
* **out_of_catalog** case right ⇔ verdict ``"unexplained"``.
* ``names_ok`` (reported): the named set alone is right (catalog: the rule above without the
  verdict; clean: nothing named); none for out-of-catalog runs, whose names are tentative.
* ``gap_ok`` (reported, not part of "right"): every axis of ``gap_after_fit`` is consistent
  with noise (``GapMeasure.consistent()``), or the verdict is ``"explained"``.
* ``contradictions`` (reported; the tests require none): where the verdict contradicts the
  analysis' own per-axis consistency (:func:`contradictions`, issue 20, item 3).

Error rates, for a test that must not tune thresholds to files: the analysis states its
family false-alarm probability α (``criterion["family_alpha"]``, 0.001 by default; 0.005
until stop 44) for a clean run, so among R clean runs the wrong ones are Binomial(R, α);
:func:`max_wrong` gives the count a test may allow at a stated confidence.

``analysis.verdict`` is read with ``getattr(…, "verdict", None)`` (older results have none).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from scipy import stats

from validation.cases import KINDS, Case, validation_set


def default_analyze(case: Case):
    """:func:`calib.gap.analyze_gap` on the case's run and stated noise variances."""
    from calib.files.course import Ensayo
    from calib.gap import analyze_gap

    return analyze_gap(Ensayo(case.tita, case.datos, case.t, source=case.id), case.noise_var)


def named_effects(analysis) -> set[tuple[str, str]]:
    """(name, axis) of every effect the analysis named."""
    return {(e.name, e.axis) for e in getattr(analysis, "effects", ())}


def _axes_match(a: str, b: str) -> bool:
    return a == b or "both" in (a, b)


def matches(expected: Iterable[tuple[str, str]], named: Iterable[tuple[str, str]],
            not_identifiable: Iterable[dict] = ()) -> bool:
    """True when ``named`` is ``expected`` up to the ties listed in ``not_identifiable``.

    Every expected effect is named, or tied (one ``not_identifiable`` entry lists both names)
    to a named effect on a matching axis; and every named effect is expected or stands for a
    tied expected one.
    """
    exp, nam = set(expected), set(named)
    found, used = exp & nam, exp & nam
    for e_name, e_axis in exp - nam:
        for entry in not_identifiable:
            names = set(entry.get("names", ()))
            if e_name not in names:
                continue
            stand_ins = {(n, a) for n, a in nam if n in names and n != e_name
                         and _axes_match(a, e_axis)}
            if stand_ins:
                found.add((e_name, e_axis))
                used |= stand_ins
    return found == exp and used == nam


def judge(case: Case, analysis) -> dict:
    """One row of the score table."""
    verdict = getattr(analysis, "verdict", None)
    named = named_effects(analysis)
    ties = tuple(getattr(analysis, "not_identifiable", ()))
    if case.kind == "catalog":
        names_ok = matches(case.expected, named, ties)
        right = names_ok and verdict == "explained"
    elif case.kind == "clean":
        names_ok = not named
        right = names_ok and verdict == "nothing_detected"
    else:
        names_ok = None  # any name may be tentative: only the verdict counts
        right = verdict == "unexplained"
    consistent = (getattr(analysis, "adequacy", None) or {}).get("consistent")
    if consistent is not None:  # the analysis' own judgement: against the stated noise
        gap_ok = all(consistent.values())
    else:
        gap_after = getattr(analysis, "gap_after_fit", None) or {}
        gap_ok = bool(gap_after) and all(m.consistent() for m in gap_after.values())
    return {"id": case.id, "kind": case.kind, "design": case.design, "n": case.n,
            "expected": sorted(case.expected), "named": sorted(named), "verdict": verdict,
            "right": bool(right), "names_ok": names_ok, "gap_ok": bool(gap_ok),
            "size_sigma": dict(case.size_sigma),
            "contradictions": (contradictions(case.id, analysis)
                               if getattr(analysis, "adequacy", None) else [])}


def contradictions(case_id: str, analysis) -> list[str]:
    """Where the verdict contradicts the per-axis consistency (one verdict, issue 20 item 3).

    The verdict and ``adequacy["consistent"]`` come from the same battery (the gap after's χ²
    against the stated noise and its signatures are checks of it), so on every run:
    "explained" or "nothing_detected" ⇒ every axis consistent and the gap after's χ²/dof
    inside its two-sided band at the battery's per-check level (unless a noise level is
    named on that axis); "explained" ⇒ something named, "nothing_detected" ⇒ nothing;
    "unexplained" ⇒ at least one axis not consistent and every failed check names its axis
    ("x", "y" or "both"). Returns one line per contradiction (none: consistent)."""
    from calib.conventions import AXES

    out = []
    verdict = analysis.verdict
    consistent = analysis.adequacy["consistent"]
    alpha = analysis.adequacy["alpha_check"]
    if verdict in ("explained", "nothing_detected"):
        if not all(consistent.values()):
            out.append(f"{case_id}: verdict {verdict} but consistent = {consistent}")
        for k, ax in enumerate(AXES):
            gm = analysis.gap_after_fit[ax]
            lo, hi = gm.chi2_band(alpha)
            if not analysis.final.state.axes[k].noise_free and not lo <= gm.chi2_dof <= hi:
                out.append(f"{case_id}: verdict {verdict} but χ²/dof {ax} = "
                           f"{gm.chi2_dof:.4g} outside [{lo:.4g}, {hi:.4g}]")
    if verdict == "explained" and not analysis.effects:
        out.append(f"{case_id}: explained with nothing named")
    if verdict == "nothing_detected" and analysis.effects:
        out.append(f"{case_id}: nothing detected but {analysis.named} named")
    if verdict == "unexplained":
        if all(consistent.values()):
            out.append(f"{case_id}: unexplained but every axis consistent")
        if not analysis.unexplained or any(u["axis"] not in (*AXES, "both")
                                           for u in analysis.unexplained):
            out.append(f"{case_id}: unexplained without an axis-named signature")
    return out


def max_wrong(count: int, rate: float, confidence: float = 0.999) -> int:
    """Largest number of wrong runs among ``count`` that a per-run error ``rate`` explains at
    ``confidence`` (the ``confidence`` quantile of Binomial(count, rate))."""
    return int(stats.binom.ppf(confidence, count, rate))


@dataclass(frozen=True)
class Score:
    """Rows (one per case, :func:`judge`) and the time the analysis took, s."""

    rows: tuple[dict, ...]
    seconds: float = 0.0

    def summary(self, by: str = "kind") -> list[dict]:
        """Per ``by`` ("kind" or "design"): ``{by, cases, right, rate, names_ok, gap_ok}``
        (``names_ok``: the named set alone is right, verdict aside; clean and catalog)."""
        groups: dict[str, list[dict]] = {}
        for r in self.rows:
            groups.setdefault(r[by], []).append(r)
        order = KINDS if by == "kind" else sorted(groups)
        return [{by: g, "cases": len(groups[g]), "right": sum(r["right"] for r in groups[g]),
                 "rate": sum(r["right"] for r in groups[g]) / len(groups[g]),
                 "names_ok": sum(bool(r["names_ok"]) for r in groups[g]),
                 "gap_ok": sum(r["gap_ok"] for r in groups[g])}
                for g in order if g in groups]

    def wrong(self, kind: str | None = None) -> list[dict]:
        return [r for r in self.rows if not r["right"] and kind in (None, r["kind"])]

    def to_markdown(self) -> str:
        def pairs(ps):
            return ", ".join(f"{n} ({a})" for n, a in ps) or "—"

        def yes(v):
            return "—" if v is None else ("yes" if v else "no")

        out = ["| id | kind | design | expected | named | verdict | right | names_ok | gap_ok |",
               "|---|---|---|---|---|---|---|---|---|"]
        for r in self.rows:
            out.append(f"| {r['id']} | {r['kind']} | {r['design']} | {pairs(r['expected'])} | "
                       f"{pairs(r['named'])} | {r['verdict']} | {yes(r['right'])} | "
                       f"{yes(r['names_ok'])} | {yes(r['gap_ok'])} |")
        for by in ("kind", "design"):
            out += ["", f"| {by} | cases | right | rate | names_ok | gap_ok |",
                    "|---|---|---|---|---|---|"]
            out += [f"| {s[by]} | {s['cases']} | {s['right']} | {s['rate']:.0%} | "
                    f"{s['names_ok']} | {s['gap_ok']} |" for s in self.summary(by)]
        total = sum(r["right"] for r in self.rows)
        contra = [line for r in self.rows for line in r.get("contradictions", [])]
        out += ["", f"{total}/{len(self.rows)} right; {len(contra)} contradictions between "
                    f"the verdict and the per-axis consistency; analysis time "
                    f"{self.seconds:.1f} s", *contra]
        return "\n".join(out)


def score(cases: Iterable[Case], analyze: Callable | None = None) -> Score:
    """Run ``analyze(case)`` (default :func:`default_analyze`) on every case and judge it."""
    analyze = analyze or default_analyze
    rows, spent = [], 0.0
    for case in cases:
        t0 = time.perf_counter()
        analysis = analyze(case)
        spent += time.perf_counter() - t0
        rows.append(judge(case, analysis))
    return Score(rows=tuple(rows), seconds=spent)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m validation.score",
                                     description="Score the gap analysis on the validation set "
                                                 "(markdown on stdout).")
    parser.add_argument("--seed", type=int, default=0, help="seed of the set (default 0)")
    parser.add_argument("--clean", type=int, default=22,
                        help="number of clean runs (default 22, two per design)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    cases = validation_set(args.seed, args.clean)
    generated = time.perf_counter() - t0
    result = score(cases)
    sys.stdout.write(result.to_markdown() + f"\ngeneration time {generated:.1f} s\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
