"""Wire formats: :mod:`station.protocol.v1` (framed, ours) and :mod:`station.protocol.legacy` (the rig's old PSoC).

Both are pure codecs without I/O; :mod:`station.link` runs a session over a port.
"""

PROTOCOLS = ("v1", "legacy")
