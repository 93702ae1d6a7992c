"""Any message, decoded with nothing but its definition: its fields as named numpy columns (``fields``, ``decoder``)
and Foxglove's message paths that name them (``message_path``). Imports ``msgs``' typestore and ``errors``.
"""
