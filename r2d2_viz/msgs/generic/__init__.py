"""Any message, decoded with nothing but its definition: its fields as named numpy columns (``fields``, ``decoder``),
Foxglove's message paths that name them (``message_path``), and the definitions known to be Humble's layout
(``known_layouts``). Imports ``msgs``' typestore and ``errors``.
"""
