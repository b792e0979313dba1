"""Independent references of the valve dynamics: the scipy solver (``valve_ivp``), the C
kernel (``c_valve``), their shared observations (``valve_outputs``) and the accuracy
measurements against them (``accuracy``)."""
