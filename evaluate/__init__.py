"""Exercises and evaluation at scale: scenario suites and match series, run headless on a
virtual clock, in a local process pool or on a Dask cluster, reported as JSON and HTML
(docs/evaluate.md)."""
