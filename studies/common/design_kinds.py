"""Kinds of design that the layers below :mod:`studies.define` need to tell apart."""

SAMPLING_DESIGNS = ("saltelli", "sobol", "lhs")
"""Designs that sample their factors: every design point has values of its own."""
