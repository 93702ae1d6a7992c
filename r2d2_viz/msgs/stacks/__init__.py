"""The navigation and perception stacks' display messages: nav2's particle clouds and voxel grids, vision_msgs'
2D and 3D detections (their definitions, carried for live graphs, and their decoders)."""
