"""RViz 2's displays beyond the first ones (issue 46): AccelStamped, the scalar sensors' points, InteractiveMarkers,
DepthCloud and Effort (``joined``: the decoding that needs more than one message). Imports ``msgs``' helpers.
"""
