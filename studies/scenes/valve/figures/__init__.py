"""The valve scenes' own figures, each built from a results Dataset: the jump-speed map and
the error-vs-cost chart (``maps``), the spring-model ladder (``ladder``) and the surge sweep
(``surge``). Imported on use: a study that writes no figure loads no matplotlib."""
