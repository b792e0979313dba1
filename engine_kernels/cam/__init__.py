"""Cam kernels: lift laws, multi-segment profiles, contact criteria, scene batches (physics §2).

One physical concept per module:

* :mod:`~engine_kernels.cam.lift_laws` — rise–return lift laws h(θ) of one event;
* :mod:`~engine_kernels.cam.multi_segment` — the six-segment profile with ramps;
* :mod:`~engine_kernels.cam.contact` — curvature, lubrication, EHL film, Hertz stress, contact
  force and spring margin at one cam angle;
* :mod:`~engine_kernels.cam.kinematics` — parameter columns and kinematics batch drivers;
* :mod:`~engine_kernels.cam.loads` — geometry and load batch drivers.
"""
