"""Stage 3, the models: the paper's networks and ours (no data, no training loop here).

``base`` (sizes from the config, input checks, the spec checkpoints record) -> ``paper`` (encoder,
decoder, reward net, the two pipelines of Figs. 3-4) -> ``safety`` (the joint model of Fig. 9,
end-to-end safety nets, the distilled survival net, probes) and ``rnn`` (the look-ahead of Fig. 10).
"""
