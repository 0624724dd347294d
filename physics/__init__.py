"""theoria.physics — pure numerics of Euler's rotational celestial mechanics.

numpy/scipy (and numba for the rigid-body hot loop) only: no UI, no printing, no file reads.
"""
