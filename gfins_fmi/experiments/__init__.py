"""Experiments: ``gfins demo`` (``demo``: the main job end to end) and the reproductions of
published experiments (``qin``: seed 000's 6- vs 9-accelerometer comparison, Qin, Xu, Li;
``seed001``: seed 001's vehicle test of a rotating INS). Import from the modules."""
