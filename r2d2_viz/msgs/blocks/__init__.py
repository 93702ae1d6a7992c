"""Block decoders (issue 46, item 3): a topic's messages of a window decoded together with numpy over their CDR
bytes, for ``r2d2_viz.msgs.registry.BLOCK_DECODERS``."""
