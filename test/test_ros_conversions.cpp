// The ros layer's conversions, without a master: joint values onto state vectors, poses, shapes
// and point clouds, each against an independent construction and with every malformed case.
#include <gtest/gtest.h>

#include <memory>

#include <cmath>
#include <cstring>
#include <limits>

#include <Eigen/Geometry>
#include <sensor_msgs/PointField.h>

#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/ros/conversions.h"

namespace bvh_collision {
namespace {

RobotModel demo_arm() {
  return RobotModel::from_urdf(*load_robot_description_file(std::string(BVH_COLLISION_SOURCE_DIR) + "/urdf/demo_arm.urdf"),
                               PackageResolver({}));
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const RequestError& e) {
    return e.what();
  }
  return "";
}

TEST(JointValueMap, NamesMapToStateVariables) {
  const RobotModel model = demo_arm();
  const JointValueMap map(model);
  std::vector<std::string> warnings;
  const auto columns = map.columns(model.variable_names(), warnings);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    EXPECT_EQ(columns[i], int(i));
  }
  EXPECT_TRUE(warnings.empty());
  std::vector<double> state(model.variable_count(), 0.0);
  const std::vector<std::string> names = {"joint3", "joint1"};
  map.write(map.columns(names, warnings), std::vector<double>{0.5, -0.25}.data(), names, state, warnings);
  EXPECT_EQ(state[model.joints()[model.joint_index("joint3")].variable], 0.5);
  EXPECT_EQ(state[model.joints()[model.joint_index("joint1")].variable], -0.25);
  EXPECT_TRUE(warnings.empty());
}

// The node replaces its checker as proxy levels are built, and the model the map was made from
// goes with the old one: the map must not depend on it (it once kept a pointer, and every
// request after the first swap failed with "unknown joint").
TEST(JointValueMap, OutlivesTheModelItWasMadeFrom) {
  auto model = std::make_unique<RobotModel>(demo_arm());
  const std::vector<std::string> names = model->variable_names();
  const JointValueMap map(*model);
  model.reset();
  std::vector<std::string> warnings;
  const auto columns = map.columns(names, warnings);
  ASSERT_EQ(columns.size(), names.size());
  for (std::size_t i = 0; i < columns.size(); ++i) {
    EXPECT_EQ(columns[i], int(i));
  }
  EXPECT_TRUE(map.knows("joint1"));
}

TEST(JointValueMap, BadNamesAndValuesAreErrors) {
  const RobotModel model = demo_arm();
  const JointValueMap map(model);
  std::vector<std::string> warnings;
  EXPECT_EQ(error_of([&] { map.columns({"joint1", "wrist"}, warnings); }), "unknown joint 'wrist' (robot 'demo_arm')");
  EXPECT_EQ(error_of([&] { map.columns({"joint1", "joint1"}, warnings); }), "joint 'joint1' is named twice");
  EXPECT_NE(error_of([&] { map.columns({"hand_joint"}, warnings); }).find("fixed"), std::string::npos);
  std::vector<double> state(model.variable_count(), 0.0);
  const std::vector<std::string> one = {"joint2"};
  const auto columns = map.columns(one, warnings);
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                     -std::numeric_limits<double>::infinity()}) {
    const std::vector<double> before = state;
    EXPECT_NE(error_of([&] { map.write(columns, &bad, one, state, warnings); }), "");
    EXPECT_EQ(state, before) << "a rejected value was written";
  }
}

TEST(JointValueMap, OutsideLimitsWarnsAndMimicIsIgnored) {
  const RobotModel model = demo_arm();
  const JointValueMap map(model);
  std::vector<std::string> warnings;
  std::vector<double> state(model.variable_count(), 0.0);
  const std::vector<std::string> names = {"joint2", "finger_joint_right"};
  const auto columns = map.columns(names, warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], "joint 'finger_joint_right' mimics 'finger_joint_left': its value is ignored");
  EXPECT_EQ(columns[1], -1);
  map.write(columns, std::vector<double>{2.5, 0.04}.data(), names, state, warnings);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[1], "joint 'joint2' = 2.5 is outside its limits [-2, 2]");
  EXPECT_EQ(state[model.joints()[model.joint_index("joint2")].variable], 2.5) << "still answered with the value";
  EXPECT_EQ(join_warnings({"a", "b", "c"}, 2), "a; b; and 1 more");
}

TEST(JointValueMap, NeutralStateIsZeroClampedIntoLimits) {
  const RobotModel model = demo_arm();
  for (double v : neutral_state(model)) EXPECT_EQ(v, 0.0);  // every demo joint's limits contain 0
  for (const RobotJoint& j : model.joints()) {
    if (j.variable >= 0 && j.bounded) {
      EXPECT_TRUE(j.lower <= 0.0 && 0.0 <= j.upper);
    }
  }
}

TEST(Poses, QuaternionsBecomeTheRotationEigenBuilds) {
  const Eigen::AngleAxisd rotation(0.7, Vec3(1, -2, 0.5).normalized());
  const Eigen::Quaterniond q(rotation);
  geometry_msgs::Pose pose;
  pose.position.x = 1e4, pose.position.y = -2, pose.position.z = 3;
  // A quaternion that is a little off unit length is normalised, as tf2 does.
  pose.orientation.x = q.x() * 1.0005, pose.orientation.y = q.y() * 1.0005;
  pose.orientation.z = q.z() * 1.0005, pose.orientation.w = q.w() * 1.0005;
  const Transform t = to_transform(pose);
  EXPECT_TRUE(t.R.isApprox(rotation.toRotationMatrix(), 1e-12));
  EXPECT_EQ(t.t, Vec3(1e4, -2, 3));
  EXPECT_TRUE(is_rigid(t));
  const Transform back = to_transform(to_pose_msg(t));
  EXPECT_TRUE(back.R.isApprox(t.R, 1e-12));
  pose.orientation.w = 0.0, pose.orientation.x = pose.orientation.y = pose.orientation.z = 0.0;
  EXPECT_NE(error_of([&] { to_transform(pose); }).find("not a unit quaternion"), std::string::npos);
  pose.orientation.w = 1.0;
  pose.position.y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(error_of([&] { to_transform(pose); }).find("NaN"), std::string::npos);
}

// shape_msgs with the messages' own dimension indices (CYLINDER_HEIGHT = 0, CYLINDER_RADIUS = 1:
// the opposite of the old CollisionShape's [radius, length]).
TEST(Shapes, EverySolidPrimitiveWithItsDimensionIndicesAndItsErrors) {
  using shape_msgs::SolidPrimitive;
  SolidPrimitive s;
  s.type = SolidPrimitive::BOX;
  s.dimensions = {0.1, 0.2, 0.3};
  EXPECT_EQ(to_object_shape(s).size, Vec3(0.1, 0.2, 0.3));
  s.type = SolidPrimitive::SPHERE;
  s.dimensions = {0.4};
  EXPECT_EQ(to_object_shape(s).radius, 0.4);
  s.type = SolidPrimitive::CYLINDER;
  s.dimensions.assign(2, 0.0);
  s.dimensions[SolidPrimitive::CYLINDER_HEIGHT] = 0.5;
  s.dimensions[SolidPrimitive::CYLINDER_RADIUS] = 0.1;
  const ObjectShape cylinder = to_object_shape(s);
  EXPECT_EQ(cylinder.kind, ObjectShape::Kind::kCylinder);
  EXPECT_EQ(cylinder.length, 0.5);
  EXPECT_EQ(cylinder.radius, 0.1);
  s.type = SolidPrimitive::CONE;
  s.dimensions[SolidPrimitive::CONE_HEIGHT] = 0.3;
  s.dimensions[SolidPrimitive::CONE_RADIUS] = 0.05;
  const ObjectShape cone = to_object_shape(s);
  EXPECT_EQ(cone.kind, ObjectShape::Kind::kCone);
  EXPECT_EQ(cone.length, 0.3);
  EXPECT_EQ(cone.radius, 0.05);
  s.dimensions = {0.1};
  EXPECT_EQ(error_of([&] { to_object_shape(s); }), "CONE needs 2 dimensions (height, radius), got 1");
  s.dimensions = {0.3, -0.05};
  EXPECT_NE(error_of([&] { to_object_shape(s); }).find("CONE dimensions must be positive"), std::string::npos);
  s.type = 0;
  EXPECT_NE(error_of([&] { to_object_shape(s); }).find("unknown solid primitive type 0"), std::string::npos);
}

TEST(Shapes, MeshesAndResourcesAndTheirErrors) {
  const PackageResolver resolver({});
  shape_msgs::Mesh m;
  m.vertices.resize(3);
  m.vertices[1].x = 1.0;
  m.vertices[2].y = 1.0;
  m.triangles.resize(1);
  m.triangles[0].vertex_indices = {0, 1, 2};
  const ObjectShape tri = to_object_shape(m);
  ASSERT_TRUE(tri.mesh);
  EXPECT_EQ(tri.mesh->triangles.size(), 1u);
  EXPECT_EQ(tri.mesh->vertices[1], Vec3(1, 0, 0));
  m.triangles[0].vertex_indices = {0, 1, 3};
  EXPECT_NE(error_of([&] { to_object_shape(m); }).find("index 3 is out of range"), std::string::npos);
  m.triangles.clear();
  EXPECT_NE(error_of([&] { to_object_shape(m); }).find("at least one triangle"), std::string::npos);
  geometry_msgs::Vector3 scale;
  EXPECT_NE(error_of([&] { mesh_resource_shape("package://no_such_package/mesh.stl", scale, resolver); })
                .find("mesh 'package://no_such_package/mesh.stl'"),
            std::string::npos);
  // A URI with a NUL inside is refused (a C string stopped at it and opened another file), and
  // the message writes the NUL as \x00 instead of ending there.
  EXPECT_EQ(error_of([&] { mesh_resource_shape(std::string("/tmp/a.stl\0x", 12), scale, resolver); }),
            "mesh '/tmp/a.stl\\x00x': the URI holds a control character (U+0000 at byte 10)");
  scale.x = 1.0;  // y and z zero: not "all zeros"
  EXPECT_NE(error_of([&] { mesh_resource_shape("/a.stl", scale, resolver); }).find("non-zero on every axis"),
            std::string::npos);
}

TEST(Shapes, AnObjectsShapesInOrderWithTheirPoses) {
  const PackageResolver resolver({});
  SetCollisionObject::Request req;
  EXPECT_NE(error_of([&] { object_shapes(req, resolver); }).find("has no shape"), std::string::npos);
  shape_msgs::SolidPrimitive box;
  box.type = shape_msgs::SolidPrimitive::BOX;
  box.dimensions = {0.1, 0.1, 0.1};
  req.primitives = {box, box};
  geometry_msgs::Pose pose;
  pose.orientation.w = 1.0;
  req.primitive_poses = {pose};
  EXPECT_EQ(error_of([&] { object_shapes(req, resolver); }), "primitives: 2 shapes but 1 poses (one pose per shape)");
  pose.position.z = 0.5;
  req.primitive_poses.push_back(pose);
  req.meshes.resize(1);
  req.meshes[0].vertices.resize(3);
  req.meshes[0].triangles.resize(1);
  req.meshes[0].triangles[0].vertex_indices = {0, 1, 2};
  req.mesh_poses = {pose};
  const std::vector<PlacedShape> shapes = object_shapes(req, resolver);
  ASSERT_EQ(shapes.size(), 3u);
  EXPECT_EQ(shapes[0].pose.t, Vec3::Zero());
  EXPECT_EQ(shapes[1].pose.t, Vec3(0, 0, 0.5));
  EXPECT_TRUE(shapes[2].shape.mesh);
  req.primitives[1].dimensions.pop_back();
  EXPECT_EQ(error_of([&] { object_shapes(req, resolver); }).rfind("primitives[1]: BOX needs 3 dimensions", 0), 0u);
}

TEST(Clouds, RoundTripAndOrganisedRowsWithPadding) {
  const std::vector<ScanPoint> points = {{1, 2, 3}, {-4, 5.5f, 6}, {NAN, 0, 0}};
  const auto back = cloud_points(to_cloud_msg(points, "camera"));
  ASSERT_EQ(back.size(), 3u);
  EXPECT_EQ(back[0], points[0]);
  EXPECT_EQ(back[1], points[1]);
  EXPECT_TRUE(std::isnan(back[2].x())) << "invalid points are kept: insertion counts them";

  // Built by hand: 2 x 2, FLOAT64 z before x and y, a 4-byte pad after each row.
  sensor_msgs::PointCloud2 c;
  c.height = 2, c.width = 2, c.point_step = 24, c.row_step = 2 * 24 + 4;
  const char* names[] = {"z", "x", "y"};
  const std::uint8_t types[] = {sensor_msgs::PointField::FLOAT64, sensor_msgs::PointField::FLOAT32,
                                sensor_msgs::PointField::FLOAT32};
  const std::uint32_t offsets[] = {0, 8, 12};
  for (int i = 0; i < 3; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i], f.datatype = types[i], f.offset = offsets[i], f.count = 1;
    c.fields.push_back(f);
  }
  c.data.assign(c.row_step * 2, 0);
  for (int r = 0; r < 2; ++r) {
    for (int k = 0; k < 2; ++k) {
      std::uint8_t* p = &c.data[r * c.row_step + k * c.point_step];
      const double z = 10 * r + k;
      const float x = float(r), y = float(k);
      std::memcpy(p, &z, 8), std::memcpy(p + 8, &x, 4), std::memcpy(p + 12, &y, 4);
    }
  }
  const auto organised = cloud_points(c);
  ASSERT_EQ(organised.size(), 4u);
  EXPECT_EQ(organised[3], ScanPoint(1, 1, 11));
  EXPECT_EQ(organised[1], ScanPoint(0, 1, 1));
}

TEST(Clouds, MalformedCloudsAreErrors) {
  const sensor_msgs::PointCloud2 good = to_cloud_msg({{1, 2, 3}, {4, 5, 6}}, "camera");
  auto no_z = good;
  no_z.fields.pop_back();
  EXPECT_EQ(error_of([&] { cloud_points(no_z); }), "cloud has no field 'z'");
  auto int_x = good;
  int_x.fields[0].datatype = sensor_msgs::PointField::INT32;
  EXPECT_NE(error_of([&] { cloud_points(int_x); }).find("'x' is not FLOAT32 or FLOAT64"), std::string::npos);
  auto short_data = good;
  short_data.data.pop_back();
  EXPECT_NE(error_of([&] { cloud_points(short_data); }).find("cloud data holds 23 bytes"), std::string::npos);
  auto beyond = good;
  beyond.fields[2].offset = 9;
  EXPECT_NE(error_of([&] { cloud_points(beyond); }).find("beyond point_step"), std::string::npos);
  auto narrow_rows = good;
  narrow_rows.row_step = 12;
  EXPECT_NE(error_of([&] { cloud_points(narrow_rows); }).find("row_step"), std::string::npos);
  auto big_endian = good;
  big_endian.is_bigendian = true;
  EXPECT_NE(error_of([&] { cloud_points(big_endian); }).find("big-endian"), std::string::npos);
}

}  // namespace
}  // namespace bvh_collision
