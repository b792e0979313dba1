"""The cam–rocker–valve linkage the ``rocker`` and ``valve`` scenes share (physics §3): the
flat-tappet law (``tappet``), the linkage [R1]–[R6] per distinct parameter set with its caches
and kinematic outputs (``scene``), its declarations (``parameters``), input checks
(``checks``), the valve-lift figure (``figures``) and the status table (``summaries``).

"Linkage" is the cam, tappet, rocker and valve geometry; "chain" means only the coil-mass
spring chain [V4] (:mod:`engine_kernels.valvetrain.spring_chain`)."""
