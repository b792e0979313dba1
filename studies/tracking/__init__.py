"""The run store: the registry (an index over the run folders, never the truth), run records and their liveness, checkpoints, trash and garbage collection, re-indexing, queries and exports (CSV/Parquet, MLflow).

May import: studies.report.write and everything below it.
"""
