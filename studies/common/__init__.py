"""Shared by every layer, scenes included: SI units, bounded file reads, text made safe for terminals and reports, labels, and the figure kit (style, layout, summary tables).

May import: engine_kernels and the standard scientific stack; nothing else of studies.
"""
