"""Stage 2, the data: ``io`` (atomic writes, checked reads) -> ``dataset`` (the on-disk layout) ->
``collect`` (the random policy's videos) -> ``splits`` (train/validation), ``labels`` (ground truth
asked of the simulator), ``calibration`` (the obstacle radii behind the paper's 4.4) -> ``store``
(the artifact store)."""
