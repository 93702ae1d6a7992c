"""Message definitions known to be Humble's layout, so that a bag carrying one needs no typestore to say so
(building rosbags' Humble store and comparing took a fifth of the 1 h JointState bag's work beyond the imports).

Each entry: the first 128 bits of SHA-256 of ``type NUL encoding NUL definition``, for the definitions rosbags'
writer puts in a bag (``Typestore.generate_msgdef(type, ros_version=2)`` of its Humble store) of the types the app
decodes. A definition not listed goes the long way (:func:`r2d2_viz.msgs.definitions.to_humble`);
``tests/msgs/generic/test_known_layouts.py`` checks every entry against that long way, and that the list is complete.
"""

from __future__ import annotations

import hashlib

TYPES = (
    "diagnostic_msgs/msg/DiagnosticArray",
    "geometry_msgs/msg/AccelStamped",
    "geometry_msgs/msg/PointStamped",
    "geometry_msgs/msg/PolygonStamped",
    "geometry_msgs/msg/PoseArray",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "geometry_msgs/msg/TwistStamped",
    "geometry_msgs/msg/WrenchStamped",
    "nav_msgs/msg/GridCells",
    "nav_msgs/msg/OccupancyGrid",
    "nav_msgs/msg/Odometry",
    "nav_msgs/msg/Path",
    "rcl_interfaces/msg/Log",
    "sensor_msgs/msg/BatteryState",
    "sensor_msgs/msg/CameraInfo",
    "sensor_msgs/msg/CompressedImage",
    "sensor_msgs/msg/FluidPressure",
    "sensor_msgs/msg/Illuminance",
    "sensor_msgs/msg/Image",
    "sensor_msgs/msg/Imu",
    "sensor_msgs/msg/JointState",
    "sensor_msgs/msg/LaserScan",
    "sensor_msgs/msg/NavSatFix",
    "sensor_msgs/msg/PointCloud",
    "sensor_msgs/msg/PointCloud2",
    "sensor_msgs/msg/Range",
    "sensor_msgs/msg/RelativeHumidity",
    "sensor_msgs/msg/Temperature",
    "std_msgs/msg/Bool",
    "std_msgs/msg/Float32",
    "std_msgs/msg/Float64",
    "std_msgs/msg/Int16",
    "std_msgs/msg/Int32",
    "std_msgs/msg/Int64",
    "std_msgs/msg/Int8",
    "std_msgs/msg/String",
    "std_msgs/msg/UInt16",
    "std_msgs/msg/UInt32",
    "std_msgs/msg/UInt64",
    "std_msgs/msg/UInt8",
    "tf2_msgs/msg/TFMessage",
    "visualization_msgs/msg/InteractiveMarkerUpdate",
    "visualization_msgs/msg/Marker",
    "visualization_msgs/msg/MarkerArray",
)
"""The types listed."""

KNOWN = frozenset(
    (
        "0a2c4b15d90c4525ef01da543e314451",  # diagnostic_msgs/msg/DiagnosticArray
        "071ff2345d2793bf6acedbff83831cf1",  # geometry_msgs/msg/AccelStamped
        "42e4d7bfe08fffa4d6cfceeaf6e9aed5",  # geometry_msgs/msg/PointStamped
        "a651b9710cef03bf731be5a986cee94e",  # geometry_msgs/msg/PolygonStamped
        "2c04f5c1307896d39a58beebfa09e7b1",  # geometry_msgs/msg/PoseArray
        "47f5b95a804b21f279e7342dd9b13e64",  # geometry_msgs/msg/PoseStamped
        "6b95279f70f04b20beb962a769932b15",  # geometry_msgs/msg/PoseWithCovarianceStamped
        "b64e7424772b998ce8f3552244bdcbe3",  # geometry_msgs/msg/TwistStamped
        "04af237cfd66eeeffa76f7721abd4f24",  # geometry_msgs/msg/WrenchStamped
        "0f8af89e72404c93af4f244f1424127e",  # nav_msgs/msg/GridCells
        "22dbafead2aa438e0dbd1fcffc9647a0",  # nav_msgs/msg/OccupancyGrid
        "70d3e2a33d4b791244830477b11768d4",  # nav_msgs/msg/Odometry
        "fae5f41dc65792650fae56f7caff6666",  # nav_msgs/msg/Path
        "43dac2397cf78df70d2a196ccdd59e23",  # rcl_interfaces/msg/Log
        "c18347163b7bbf752c78a0293bdfda77",  # sensor_msgs/msg/BatteryState
        "d913349147bf155f15c98d95eda030f0",  # sensor_msgs/msg/CameraInfo
        "f727f58dec32e49b2fdd4326c56d0244",  # sensor_msgs/msg/CompressedImage
        "9d5d8c0cc19f95497c2a1926016a6dd3",  # sensor_msgs/msg/FluidPressure
        "2d07bd7f58587c58ec00278bc13529ed",  # sensor_msgs/msg/Illuminance
        "23913cbbad65f8d0c3f905712cd124b1",  # sensor_msgs/msg/Image
        "5ddef5fa4a70a723af58c086097add99",  # sensor_msgs/msg/Imu
        "bdb3838d4b83bb374fbdbc2a0b9dc758",  # sensor_msgs/msg/JointState
        "2246af67974e1d5ce43343604bececa3",  # sensor_msgs/msg/LaserScan
        "486174c701a719ccbd7f4b13addb0ce9",  # sensor_msgs/msg/NavSatFix
        "7ed43862443722e631713b9ff001c1e8",  # sensor_msgs/msg/PointCloud
        "ed9c35d0c6c3c2114ddcd11f1c068f4d",  # sensor_msgs/msg/PointCloud2
        "a7655008fe9f888fedaf44b3b7406da9",  # sensor_msgs/msg/Range
        "30073110604fdfd3596f238e0831eb3a",  # sensor_msgs/msg/RelativeHumidity
        "1c1ade300efa0afcff9fab64881fd88e",  # sensor_msgs/msg/Temperature
        "6a5e5132f3ffb3b66be5884bf00d8810",  # std_msgs/msg/Bool
        "1eea7ae7880f54a540080bc85230c57b",  # std_msgs/msg/Float32
        "018475feee87b1fc43c4ad57b6afca9b",  # std_msgs/msg/Float64
        "fc379d192d66a805250343d1b89e4db5",  # std_msgs/msg/Int16
        "a5cb72fa01df5fbc9629a6f9f79e8727",  # std_msgs/msg/Int32
        "1a3a244dc897122da48e6cc38d2f7011",  # std_msgs/msg/Int64
        "4761cd075200706b3f86d3c66e12898b",  # std_msgs/msg/Int8
        "ce652d8a9a4f6326f117eaeeda52682d",  # std_msgs/msg/String
        "4c512f980df618c97ca8615bd603279b",  # std_msgs/msg/UInt16
        "d2aa3202e7779470866ff76cdd2d7edf",  # std_msgs/msg/UInt32
        "25aed5508911d459bbef7ac107182856",  # std_msgs/msg/UInt64
        "f2a9094c7c23ace5d4f8d6ca528f990a",  # std_msgs/msg/UInt8
        "7bce0057594f2252a16382f1f8e3b06b",  # tf2_msgs/msg/TFMessage
        "292dba06ea9e9d17ef995d3f85c82105",  # visualization_msgs/msg/InteractiveMarkerUpdate
        "ceb9671c29b91bbb6d59bbb20901bd55",  # visualization_msgs/msg/Marker
        "29e8b6f67604f6c01c4a0557ace2c001",  # visualization_msgs/msg/MarkerArray
    )
)


def key(msgtype: str, encoding: str, definition: str) -> str:
    return hashlib.sha256(f"{msgtype}\0{encoding}\0{definition}".encode()).hexdigest()[:32]


def known_humble(msgtype: str, encoding: str, definition: str) -> bool:
    """Whether this definition is one of those known to be Humble's layout (no typestore needed)."""
    return key(msgtype, encoding, definition) in KNOWN
