"""Stage 4, training: ``trainer`` (one fit loop, safe resumable checkpoints) <- ``datasets`` (the
tensors each pipeline trains on) and ``inference`` (batched model calls); ``builders`` turns each
pipeline into an artifact (``get_*`` builds or loads, ``load`` only loads)."""
