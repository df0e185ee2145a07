"""Stage 6, imitation: training a planner from a privileged teacher on the states it reaches
itself (``dagger``: the memory student). It needs planners to roll out, so it sits above them."""
