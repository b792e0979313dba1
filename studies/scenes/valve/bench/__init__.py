"""The valve scene's benchmarks (``studies bench valve``): kernels, multi-mass spring, integrators."""
