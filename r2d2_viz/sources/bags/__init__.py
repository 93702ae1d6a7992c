"""Bag storages read as one protocol (:mod:`.storage`): ``.db3``, ``.mcap`` and ROS 1 ``.bag`` files, several topics
in one pass through each file's index, and :func:`.bag.open_bag` over a whole bag (folder, split files, damage).
No rerun; imports ``msgs`` and below."""
