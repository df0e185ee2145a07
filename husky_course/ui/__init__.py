"""On top of the pipeline, the user interface: ``plotting`` (figures and tables) and ``widgets``
(interactive explorers with static fallbacks)."""
