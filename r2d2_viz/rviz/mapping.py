"""What each RViz display class and property becomes in Rerun: the converter's mapping, as a table.

:func:`mapping_markdown` renders it for docs/rviz.md (a test keeps the two in step). Pure data; no rerun import.
"""

from __future__ import annotations

MAPPING: tuple[tuple[str, str, str], ...] = (
    (
        "Global Options",
        "Fixed Frame",
        "the 3D view's `SpatialInformation(target_frame=…)`; a frame the run does not "
        'have is reported like RViz\'s "Fixed Frame [map] does not exist" and the view opens on it all the same',
    ),
    ("Global Options", "Background Color", "`Background(color=…)`"),
    ("Global Options", "Frame Rate", "none: the viewer redraws at display rate"),
    ("Grid", "Enabled / Value", "`LineGrid3D(visible=…)`"),
    ("Grid", "Cell Size", "`spacing` (m)"),
    ("Grid", "Color, Alpha", "`color=(r, g, b, 255 · alpha)`"),
    ("Grid", "Plane, Offset", "`plane=Plane3D(normal, distance)`: XY, XZ or YZ through the offset"),
    ("Grid", "Reference Frame", "the view's frame (Rerun's grid lies there; another frame is noted)"),
    ("Grid", "Plane Cell Count, Normal Cell Count", "none: Rerun's grid is unbounded and fades with distance (noted)"),
    ("Grid", "Line Style", "thin lines, `stroke_width=1` UI point (Billboards noted)"),
    ("TF", "Enabled, Show Axes", "`/tf_axes/<frame>`: `TransformAxes3D` in each frame; hidden when off"),
    (
        "TF",
        "Show Arrows",
        "`/tf_arrows/<child>` (static, in the parent frame) and the moving arrows on `/tf`; hidden when off",
    ),
    ("TF", "Show Names", "`TransformAxes3D(show_frame=…)`"),
    ("TF", "Marker Scale", "axis length 0.1 m × scale"),
    ("TF", "Frames / <frame> / Value", "that frame's `/tf_axes/<frame>` hidden when false"),
    (
        "TF",
        "Tree, Frame Timeout, Update Interval",
        "none needed: the frame tree is the data; the time cursor shows the latest transform",
    ),
    ("RobotModel", "Enabled, Visual Enabled", "`/robot/visual/**` shown or hidden"),
    ("RobotModel", "Collision Enabled", "`/robot/collision/**` shown or hidden (logged either way)"),
    ("RobotModel", "Links / <link> / Value", "`/robot/visual/<link>` hidden when false"),
    ("RobotModel", "Alpha", "the URDF colours' alpha; below 1 noted"),
    (
        "RobotModel",
        "Mass Properties / Mass, Inertia",
        "`/robot/mass/<link>`: a red ball of lead of the link's mass at its centre of mass; `/robot/inertia/<link>`: "
        "the red box of equal inertia on the principal axes (RViz's shapes; as `--mass`, `--inertia`)",
    ),
    ("RobotModel", "Links / <link> / Show Axes", "`/robot/axes/<link>`: the link's axes (every link: `--link-axes`)"),
    (
        "RobotModel",
        "Description Topic, TF Prefix",
        "several robots: each RobotModel display's settings apply to the robot of its Description Topic "
        "(`/robot2/robot_description` → `/robots/robot2/**`); a TF Prefix other than the one the recording shows is "
        "noted",
    ),
    (
        "RobotModel",
        "Description Source, File",
        "none: r2d2-viz reads the URDF itself (`--urdf`, or a bag's `<namespace>/robot_description`)",
    ),
    (
        "LaserScan, PointCloud2, PointCloud, Marker, MarkerArray, Path, Odometry, Pose, PoseWithCovariance, "
        "PoseArray, Map, Polygon, PointStamped, Range, GridCells, Wrench, Twist, TwistStamped, AccelStamped, "
        "CameraInfo, Temperature, FluidPressure, Illuminance, RelativeHumidity, InteractiveMarkers, Effort, DepthCloud",
        "Topic, Enabled",
        "the topic's messages, decoded by r2d2-viz from either storage, in their TF frame on the entity of the "
        "topic's name (`/scan`), hidden when disabled (the table below says what each message becomes)",
    ),
    (
        "LaserScan, PointCloud2, PointCloud",
        "Color, Alpha, Size (m), Color Transformer",
        "flat colour and point radius; FlatColor forces the flat colour, any other transformer keeps RViz's "
        "default choice (packed RGB8, else Intensity's rainbow, else flat)",
    ),
    (
        "LaserScan, PointCloud2, PointCloud (and Range, Odometry, Pose, PoseArray, … when a config has it)",
        "Decay Time",
        "each entity the display draws on (`/scan`; Odometry's `/odom/<k>`) gets a view override "
        "`VisibleTimeRanges(timeline=time, start=cursor − N s, end=cursor)`: the messages of the last N seconds "
        "stay drawn (0, RViz's default: only the latest), each where it was received: their points, lines and "
        "arrows are logged in the fixed frame (Rerun places a range's rows at the cursor's transforms). RViz's own "
        "displays have it on clouds and scans only; Marker displays have none (each marker's lifetime applies): "
        "not mapped on markers",
    ),
    ("Map", "Color Scheme", "map, costmap or raw colours (RViz's palettes)"),
    (
        "Axes",
        "Reference Frame, Length, Radius",
        "`/rviz_axes/<name>`: three cylinders (x red, y green, z blue) Length long and Radius thick from the frame's "
        "origin (RViz's `rviz_rendering::Axes`; 1 m, 0.1 m by default)",
    ),
    (
        "TwistStamped, AccelStamped",
        "Topic",
        "linear (204, 51, 51) and angular (204, 204, 51) arrows along their vectors, as Twist (RViz 2's class names)",
    ),
    (
        "CameraInfo",
        "Far clip, Color, Alpha",
        "the frustum of the pinhole logged from the camera's K and size, Far clip deep, in Color · Alpha, 1 cm lines "
        "(a view override of `Pinhole`'s `image_plane_distance`, `color`, `line_width`); RViz's far polygon: "
        "lines only",
    ),
    (
        "Temperature, FluidPressure, Illuminance, RelativeHumidity",
        "Min Intensity, Max Intensity, Size (m)",
        "a point at the frame's origin in RViz's rainbow over [min, max] (its defaults: 0–100 inverted, "
        "98000–105000, 0–1000, 0–1), the value plotted",
    ),
    (
        "DepthCloud",
        "Depth Map Topic, Color Image Topic",
        "`<depth topic>/depth_cloud/0`: each pixel with a depth (16UC1 mm, 0 none; 32FC1 m) through the pinhole of "
        "the depth topic's `camera_info` (its P, binning, ROI), coloured by the latest image of the Color Image "
        "Topic of the same size (white without); Queue Size, Occlusion Compensation: none",
    ),
    (
        "Effort",
        "Topic, Width, Scale",
        "the JointState topic (`/joint_states` too) read as a display: at each revolute joint's child link, RViz's arc "
        "of radius 0.05 + e · Scale / 2 (e = min(abs(effort) / URDF limit, 1) + 0.05) around the axis and its arrow "
        "head, in the rainbow colour of e (`<topic>/effort/<k>`)",
    ),
    (
        "InteractiveMarkers",
        "Interactive Markers Namespace (ROS 2), Update Topic (ROS 1)",
        "`<namespace>/update`: its controls' markers at the marker's pose (`<topic>/<name>/<key>`), moved by pose "
        "updates, cleared by erases; display only (no menus, handles or feedback)",
    ),
    (
        "Odometry",
        "Keep, Position Tolerance, Angle Tolerance, Covariance",
        "a pose is kept when it moved Position Tolerance (m) or turned Angle Tolerance (rad) from the last one kept "
        "(RViz's test); the last Keep poses kept stay drawn (`/odom/<k>`); the covariance ellipsoid",
    ),
    ("Image, Camera", "Topic / Image Topic, Enabled", "a 2D view of that topic's entity beside the plots"),
    (
        "ParticleCloud",
        "Topic, Enabled, Shape, Color, Alpha, Min Arrow Length, Max Arrow Length",
        "nav2_rviz_plugins' display: an arrow a particle, its length the weight between Min and Max Arrow Length "
        "(clamped); Arrow (Flat) as `LineStrips3D` (shaft and head lines), Arrow (3D) as `Arrows3D` (shaft radius "
        "of the mean length), Axes as three `Arrows3D` (x, y, z: red, green, blue) on `<topic>/0…2`",
    ),
    (
        "Detection3DArray",
        "Topic, Enabled, Only Edge, Line Width, Alpha",
        "vision_msgs_rviz_plugins' display: `Boxes3D` (solid, or wireframe Line Width wide) coloured by class, "
        "labelled `<class> <score>` always (Show Score and ConfigPath's colour file are not read)",
    ),
    (
        "moveit_rviz_plugin/MotionPlanning, PlanningScene",
        "Scene Robot: Show Robot Visual, Show Robot Collision, Robot Alpha, Links",
        "as RobotModel when the config has none (the planning UI, scene and trajectories are noted)",
    ),
    ("Group", "Displays, Enabled", "its displays, as if at the top level (a disabled group disables them)"),
    (
        "Views: Orbit",
        "Distance, Yaw, Pitch, Focal Point, Invert Z Axis",
        "orbital `EyeControls3D`: eye "
        "at focal + distance · (cos yaw cos pitch, sin yaw cos pitch, sin pitch), looking at the focal point, "
        "up +Z (Invert Z Axis: yaw and pitch negated, up −Z)",
    ),
    (
        "Views: XYOrbit, ThirdPersonFollower",
        "as Orbit",
        "the Orbit eye and target lifted by 0.2 · distance along the camera's up (RViz's `CAMERA_OFFSET`: the "
        "focal point in the lower half of the image)",
    ),
    ("Views (ROS 1)", "Field of View", "none: Rerun's 3D view has its own (a value other than 45° is noted)"),
    (
        "Views: FPS",
        "Position, Yaw, Pitch, Roll",
        "first-person `EyeControls3D` at Position, looking along (cos pitch cos yaw, cos pitch sin yaw, −sin pitch), "
        "up turned by Roll",
    ),
    (
        "Views: TopDownOrtho",
        "X, Y, Scale, Angle",
        "looking straight down at (X, Y) from the height that shows "
        "800 px / Scale metres, the image turned by Angle (Rerun has no orthographic 3D view: noted)",
    ),
    (
        "Views: ThirdPersonFollower",
        "Target Frame",
        "`tracking_entity` follows the frame's position; RViz also turns with its yaw (noted)",
    ),
    ("Views", "Target Frame", "`tracking_entity=/tf_axes/<frame>` when not the fixed frame"),
    ("other displays, tools, panels", "Class", "none: one note each, naming the class"),
)


def mapping_markdown() -> str:
    lines = ["| RViz display class | property | Rerun counterpart |", "|---|---|---|"]
    lines.extend(f"| {cls} | {prop} | {rerun} |" for cls, prop, rerun in MAPPING)
    return "\n".join(lines)


if (
    __name__ == "__main__"
):  # python -m r2d2_viz.rviz.mapping: docs/rviz.md's table of RViz displays and their Rerun counterparts
    import argparse

    argparse.ArgumentParser(
        prog="python -m r2d2_viz.rviz.mapping",
        description="Print docs/rviz.md's table of RViz displays and their Rerun counterparts (Markdown).",
    ).parse_args()
    print(mapping_markdown())
