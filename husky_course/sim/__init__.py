"""Stage 1, the simulator: worlds, primitives, the camera, two backends, the lattice search, the env.

``world`` -> ``primitives`` -> ``camera`` -> ``base`` (the interface) -> ``fast`` (numpy) and
``pybullet_backend`` (the reference) -> ``backends`` (choose one by name) -> ``lattice`` (exact
search over primitive sequences) -> ``env`` (Gymnasium).
"""
