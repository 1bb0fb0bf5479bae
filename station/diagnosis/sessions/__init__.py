"""Sessions and drift (``station survey DIR... --diagnose``), from the bottom up: ``layout`` (a
value per session: the keys, which run is in which session, each run's effects), ``logs`` (logs
grouped into sessions, read, set aside or cut), ``drift`` (one structure on all sessions, the
effects that drift between them), ``diagnose`` (``diagnose_sessions``: the steps in order) and
``report`` (the text and report.html).

May import :mod:`station.diagnosis.answer` and the rooms below it; never the pipeline.
"""
