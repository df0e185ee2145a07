"""Stage 5, the planners: ``base`` (the protocol) -> ``classic`` (random, heuristic), ``oracle``
(exact search on the true simulator), ``reference`` (privileged references for analysis), ``mapping``,
``tracking``, ``arrivals``, ``discs``, ``memory``, ``learned`` (Algorithm 1, RNN shooting, the
distilled oracle) -> ``registry`` (any planner by name)."""
