"""Runs held against runs and against reference numbers: compare, regress, tolerance files and the pytest helper for regression tests.

May import: studies.tracking (its RunStore and records) and everything below it.
"""
