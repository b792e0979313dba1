"""The analysis rendered: analysis.txt, report.md, report.html and the figures, written from analysis.nc and results.nc.

May import: studies.analysis.analyze and everything below it.
"""
