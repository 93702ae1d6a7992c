"""Block decoders (issue 46): a window's messages of one topic decoded together, with numpy over their CDR bytes
(the table :data:`r2d2_viz.msgs.registry.BLOCK_DECODERS`)."""
