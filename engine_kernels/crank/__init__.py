"""Slider-crank kernels: kinematics, forces, multi-cylinder layouts, cycle pressure (physics §5).

One physical concept per module:

* :mod:`~engine_kernels.crank.kinematics` — parameter columns, conventions, piston and rod
  kinematics of one cylinder (batch driver);
* :mod:`~engine_kernels.crank.piston` — piston displacement, velocity, acceleration, exact
  [K1] and two-term [K2]–[K4];
* :mod:`~engine_kernels.crank.connecting_rod` — rod angle and its rates;
* :mod:`~engine_kernels.crank.forces` — gas, inertia, rod, side, tangential and radial forces
  and torque of one cylinder;
* :mod:`~engine_kernels.crank.multicylinder` — firing orders, summed torque, free forces and
  moments of a layout;
* :mod:`~engine_kernels.crank.combustion` — cylinder pressure over the four-stroke cycle.
"""
