"""Tower-crane test-rig trolley drive sizing: the ``luffing`` scene's kernels (physics §7).

* :mod:`~engine_kernels.luffing.sizing` — parameter and output columns, the batch driver;
* :mod:`~engine_kernels.luffing.drive` — the drive chain from travel resistance to bearing life;
* :mod:`~engine_kernels.luffing.guide_tube` — deflection and slope of the guide tube.
"""
