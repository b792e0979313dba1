"""The run store: one :class:`~studies.tracking.store.RunStore` per outputs root, through which every command lists, finds, tags, removes, restores and re-indexes runs; beside it the registry (an index over the run folders, never the truth), run records and their liveness, checkpoints, trash and garbage collection, re-indexing, queries and exports (CSV/Parquet, MLflow).

May import: studies.report.write and everything below it.
"""
