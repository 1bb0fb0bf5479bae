"""A replay of a log's controller in words: whether it reproduces the logged v, at which
alignment, and what the data could not decide (the audit's unchecked rows), said the same
way by ``station replay`` and ``station compare``."""

from __future__ import annotations

from station.logged.audit import Audit
from station.logged.run import REPRODUCED_TOLERANCE


def reproduction_lines(max_abs_dv: float, alignment: int | None, audit: Audit | None,
                       judged_to: int | None = None) -> list[str]:
    """The replay's verdict, then what the data could not confirm (at most two lines):
    ``"replay reproduces the logged v: max |dv| = 0 counts, alignment d = 1 (0 and 1 alike: the
    data cannot tell them apart)"`` and ``"but v is 0 on every row, ...: the data cannot
    confirm this one"``.

    Parameters
    ----------
    max_abs_dv : float
        The replay's largest |v_replayed − v_logged|, DAC counts (inf: it diverged).
    alignment : int or None
        The alignment used (None: not a closed loop).
    audit : Audit or None
        The log's audit (:attr:`station.logged.LoggedRun.audit`): its controller and
        alignment rows say what the data left undecided.
    judged_to : int or None, optional
        The row where n jumps past which the law was not judged (0: on no row, a law with
        memory on a copy that lacks ticks between its rows).

    Returns
    -------
    list of str
    """
    reproduced = max_abs_dv <= REPRODUCED_TOLERANCE
    law = None if audit is None else audit.of("controller")
    tie = None if audit is None else audit.of("alignment")
    align = "" if alignment is None else f", alignment d = {alignment}"
    if align and tie is not None and tie.data.endswith(" alike"):
        align += f" ({tie.data.removeprefix('alignment ')}: the data cannot tell them apart)"
    upto = "" if judged_to is None else (f" up to row {judged_to}, where n jumps (its memory is not in the "
                                         f"log's rows: not judged across it)")
    if judged_to == 0:  # a law with memory on a copy that lacks ticks between its rows
        return [f"replay not judged: the law's memory ran on ticks the log lacks (replayed on θ interpolated "
                f"there: max |dv| = {max_abs_dv:.3g} counts{align})"]
    verdict = "reproduces" if reproduced else "does NOT reproduce"
    lines = [f"replay {verdict} the logged v{upto}: max |dv| = {max_abs_dv:.3g} counts{align}"]
    if reproduced and law is not None and "; but " in law.evidence:
        lines.append("but " + law.evidence.split("; but ", 1)[1])
    return lines
