"""Wire formats: :mod:`station.protocol.v1` (framed, ours) and :mod:`station.protocol.legacy` (the rig's old PSoC).

Both are pure codecs without I/O; :mod:`station.link` runs a session over a port. This
package imports only :mod:`station.rig` (DT), :mod:`station.errors` and :mod:`station.rounding`.
"""

from __future__ import annotations

from station.rig import DT
from station.errors import StationError
from station.protocol import legacy

PROTOCOLS = ("v1", "legacy")


def check_ticks(protocol: str, n_ticks: int, dt: float = DT) -> None:
    """Refuse a run longer than ``protocol`` can count (the legacy device counts ticks in int16).

    Parameters
    ----------
    protocol : {"v1", "legacy"}
        The protocol of the run.
    n_ticks : int
        Ticks the run would last.
    dt : float, default :data:`station.rig.DT`
        Sample time, s (the message gives the limit in s too).

    Raises
    ------
    StationError
        ``protocol`` is "legacy" and ``n_ticks`` exceeds :data:`legacy.MAX_TICKS` (32767).
    """
    if protocol == "legacy" and n_ticks > legacy.MAX_TICKS:
        raise StationError(f"the legacy protocol counts ticks in int16: at most {legacy.MAX_TICKS} ticks "
                           f"({legacy.MAX_TICKS * dt:g} s), asked {n_ticks} ({n_ticks * dt:g} s)")
