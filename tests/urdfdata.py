"""The URDF corpus of tests/data (good and bad files) and what each bad file's error must say; shared by the
URDF checks and the command-line tests."""

from __future__ import annotations

from conftest import REPO

DATA = REPO / "tests" / "data"
BAD = DATA / "bad"
GOOD = DATA / "good"

# Every file in tests/data/bad/ -> a fragment the UrdfError message must contain.
BAD_MANIFEST: dict[str, str] = {
    "empty.urdf": "file is empty",
    "whitespace_only.urdf": "file is empty",
    "not_xml.urdf": "line 1: not well-formed XML",
    "truncated.urdf": "not well-formed XML",
    "wrong_root.urdf": "root element is <sdf>; expected <robot>",
    "no_links.urdf": "robot 't': has no <link> elements",
    "missing_parent_link.urdf": "joint 'tilt': parent link 'axs' does not exist (did you mean 'axis'?)",
    "missing_child_link.urdf": "joint 'tilt': child link 'bdy' does not exist",
    "joint_without_parent.urdf": "joint 'j': missing <parent link=...>",
    "two_roots.urdf": "robot 't': more than one root link (2: 'base', 'orphan')",
    "cycle.urdf": "closes a kinematic loop: 'a' -> 'b' -> 'a'",
    "self_loop.urdf": "joint 'jself': closes a kinematic loop: 'a' -> 'a'",
    "duplicate_link.urdf": "link 'base': duplicate link name",
    "duplicate_joint.urdf": "joint 'j': duplicate joint name",
    "link_without_name.urdf": "link #2: missing name attribute",
    "two_parents.urdf": "joint 'bc': child link 'c' is already the child of joint 'ab'",
    "unknown_joint_type.urdf": (
        "joint 'j': unknown joint type 'hinge'; "
        "expected one of revolute, continuous, prismatic, fixed, floating, planar"
    ),
    "missing_joint_type.urdf": "joint 'j': missing type attribute; expected one of revolute,",
    "revolute_without_limit.urdf": "joint 'j': revolute joint has no <limit",
    "prismatic_without_limit.urdf": "joint 'j': prismatic joint has no <limit",
    "limit_lower_inf.urdf": "joint 'j': <limit> lower=inf upper=inf leaves no position",
    "limit_lower_word.urdf": "joint 'j': <limit> lower='infinite': 'infinite' is not a finite number",
    "limit_lower_above_upper.urdf": "joint 'j': <limit> lower=1 is greater than upper=-1",
    "limit_effort_word.urdf": "joint 'j': <limit> effort='lots': 'lots' is not a finite number",
    "limit_upper_nan.urdf": "joint 'j': <limit> upper='NaN'",
    "origin_xyz_count.urdf": "joint 'j': <origin> xyz='0 0': expected 3 numbers, got 2",
    "origin_rpy_word.urdf": "joint 'j': <origin> rpy='0 zero 0': 'zero' is not a finite number",
    "origin_xyz_nan.urdf": "joint 'j': <origin> xyz='nan 0 0'",
    "origin_xyz_inf.urdf": "joint 'j': <origin> xyz='0 inf 0'",
    "origin_xyz_overflow.urdf": "'1e999' is not a finite number",
    "origin_xyz_underscore.urdf": "'1_0' is not a finite number",
    "axis_word.urdf": "joint 'j': <axis> xyz='0 0 up'",
    "axis_zero.urdf": "joint 'j': <axis> xyz='0 0 0': must not be a zero vector",
    "axis_zero_continuous.urdf": "joint 'j': <axis> xyz='0 0.0 -0': must not be a zero vector",
    "mimic_without_joint.urdf": "joint 'j': <mimic> has no joint attribute",
    "mimic_multiplier_word.urdf": "joint 'j2': <mimic> multiplier='double'",
    "mimic_offset_inf.urdf": "joint 'j2': <mimic> offset='-inf'",
    "mimic_loop.urdf": "<mimic> joints form a loop",
    "color_rgba_three.urdf": "visual #1: material 'red': <color> rgba='1 0 0': expected 4 numbers",
    "color_rgba_word.urdf": "material 'red': <color> rgba='1 0 0 opaque': 'opaque' is not a finite number",
    "color_rgba_out_of_range.urdf": "material 'red': <color> rgba='255 0 0 1': components must be in [0, 1]",
    "top_level_material_bad_rgba.urdf": "material 'white': <color> rgba='1 1 1 nan'",
    "box_size_count.urdf": "link 'arm': visual #1: <box> size='1 1': expected 3 numbers, got 2",
    "box_size_negative.urdf": "link 'arm': visual #1: <box> size='1 -1 1': must be positive",
    "box_size_zero.urdf": "link 'arm': visual #1: <box> size='1 1 0': must be positive",
    "box_size_missing.urdf": "link 'arm': visual #1: <box> has no size attribute",
    "cylinder_radius_word.urdf": "link 'arm': visual #1: <cylinder> radius='wide'",
    "cylinder_length_zero.urdf": "link 'arm': visual #1: <cylinder> length='0': must be positive",
    "cylinder_radius_missing.urdf": "link 'arm': visual #1: <cylinder> has no radius attribute",
    "sphere_radius_negative.urdf": "link 'arm': visual #1: <sphere> radius='-0.5': must be positive",
    "sphere_radius_missing.urdf": "link 'arm': visual #1: <sphere> has no radius attribute",
    "sphere_radius_nan.urdf": "link 'arm': visual #1: <sphere> radius='nan'",
    "geometry_empty.urdf": "link 'arm': visual #1: <geometry> has no shape; expected one of box, cylinder,",
    "geometry_unknown_shape.urdf": "link 'arm': visual #1: <geometry>: unknown shape <cone>; expected one of",
    "geometry_two_shapes.urdf": "link 'arm': visual #1: <geometry> has 2 shapes",
    "visual_without_geometry.urdf": "link 'arm': visual #1: <visual> has no <geometry>",
    "mesh_without_filename.urdf": "link 'arm': visual #1: <mesh> has no filename",
    "mesh_scale_count.urdf": "link 'arm': visual #1: <mesh> scale='2': expected 3 numbers, got 1",
    "collision_box_negative.urdf": "link 'arm': collision #1: <box> size='-1 1 1': must be positive",
    "inertial_mass_word.urdf": "link 'arm': <inertial>: <mass> value='heavy'",
    "not_utf8.urdf": "line 3: not valid UTF-8 (byte 0xe9",
    "utf16.urdf": "not valid UTF-8",
    "utf16_no_bom.urdf": "character U+0000 is not allowed in XML",
    "billion_laughs.urdf": "DOCTYPE declares entities",
    "xxe_file.urdf": "DOCTYPE declares entities",
    "xxe_parameter_entity.urdf": "DOCTYPE declares entities",
    "external_dtd_entity_reference.urdf": "entity reference '&passwd;' is not allowed",
    "undefined_entity.urdf": "Entity 'nbsp' not defined",
}
