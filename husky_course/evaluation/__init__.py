"""Stage 6, evaluation: ``statistics`` (exact binomial intervals), ``metrics`` (classification and
image errors), ``rollout`` (one episode, decision by decision), ``episodes`` (planners run on
held-out worlds), ``analysis`` (why episodes end as they do), ``horizons`` (prediction quality
against the horizon)."""
