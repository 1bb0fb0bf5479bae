"""Sessions and drift (``station survey DIR... --diagnose``): logs grouped into sessions and
diagnosed together (``diagnose``), the effects that drift between them (``drift``), and the
text and report.html (``report``).

May import :mod:`station.diagnosis.answer` and the rooms below it; never the pipeline.
"""
