"""On top of the pipeline, the user interface: ``plotting`` (figures and tables), ``widgets``
(live explorers in a kernel) and ``animation`` (the same explorers as self-contained JavaScript
players for the offline book)."""
