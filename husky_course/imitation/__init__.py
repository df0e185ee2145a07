"""Stage 6, training that needs planners: a planner taught by a privileged teacher on the states it
reaches itself (``dagger``: the memory student), the certificate's posterior, and the disc network
(``discs``: simulated views read by the disc planner's own perception). It sits above the planners."""
