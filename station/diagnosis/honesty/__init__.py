"""What the answer does not know: intervals and alternatives (``doubt``), what stays
unexplained (``unexplained``) and the explanations a diagnosis leaves open (``rivals``).

May import :mod:`station.diagnosis.search` and the rooms below it.
"""
