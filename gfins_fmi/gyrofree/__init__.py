"""Gyro-free navigation with accelerometer arrays: the array and the 9-accelerometer
solver of seed 000 (``array``), what an array measures (``geometry``: layouts, solver
maps; ``stability``: the rate loop; ``report``: all of it in words), the rate solver
(``rate_solver``), the navigator (``navigator``) and the array's sensor errors
(``array_errors``). Model and strategies: ``csrc/gyrofree/gf_gfins.h``.

Import from the modules: this package's ``__init__`` imports nothing (``import gfins_fmi``
loads only what its own names need).
"""
