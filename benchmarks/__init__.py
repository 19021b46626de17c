"""Timing and accuracy benchmarks, run by ``make bench`` (not part of ``make test``)."""
