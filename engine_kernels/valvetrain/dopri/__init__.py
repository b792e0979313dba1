"""Adaptive Dormand–Prince 5(4) for the valve [V2], switches located on its dense output, one case at a time: the driver (integrate), one step (step), observations (observe)."""
