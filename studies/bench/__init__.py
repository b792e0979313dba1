"""Benchmarks: throughput figures printed and written as JSON, alternatives measured in the same run and reported as ratios (never asserted in tests).

May import: studies.tracking (its RunStore and records) and everything below it.
"""
