#include "bvh_collision/ros/conversions.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>
#include <sstream>

#include <sensor_msgs/PointField.h>

#include "bvh_collision/robot/mesh_loader.h"

namespace bvh_collision {

namespace {

// A name from a request, quoted for a message: control characters (a NUL would end the message
// for any reader of a C string) are written as \xNN.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (const char c : s) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out += c;
      continue;
    }
    char code[5];
    std::snprintf(code, sizeof code, "\\x%02X", static_cast<unsigned>(u));
    out += code;
  }
  return out + "'";
}

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace

JointValueMap::JointValueMap(const RobotModel& model)
    : model_(model),
      lower_(model.variable_count(), -INFINITY),
      upper_(model.variable_count(), INFINITY),
      bounded_(model.variable_count(), false) {
  for (const RobotJoint& joint : model.joints()) {
    if (joint.variable < 0 || !joint.bounded) continue;
    lower_[joint.variable] = joint.lower;
    upper_[joint.variable] = joint.upper;
    bounded_[joint.variable] = true;
  }
}

bool JointValueMap::knows(const std::string& name) const { return model_.joint_index(name) >= 0; }

std::vector<int> JointValueMap::columns(const std::vector<std::string>& names,
                                        std::vector<std::string>& warnings) const {
  std::vector<int> columns;
  columns.reserve(names.size());
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (!seen.insert(name).second) throw RequestError("joint " + quoted(name) + " is named twice");
    const int j = model_.joint_index(name);
    if (j < 0) throw RequestError("unknown joint " + quoted(name) + " (robot '" + model_.name() + "')");
    const RobotJoint& joint = model_.joints()[j];
    if (joint.mimic >= 0) {
      warnings.push_back("joint " + quoted(name) + " mimics " + quoted(model_.joints()[joint.mimic].name) +
                         ": its value is ignored");
      columns.push_back(-1);
      continue;
    }
    if (joint.variable < 0) {
      throw RequestError("joint " + quoted(name) + " has no single value (fixed, floating or planar joint)");
    }
    columns.push_back(joint.variable);
  }
  return columns;
}

void JointValueMap::write(const std::vector<int>& columns, const double* values,
                          const std::vector<std::string>& names, std::vector<double>& state,
                          std::vector<std::string>& warnings) const {
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const double v = values[i];
    if (!std::isfinite(v)) throw RequestError("joint " + quoted(names[i]) + " has value " + number(v));
    const int c = columns[i];
    if (c < 0) continue;
    if (bounded_[c] && (v < lower_[c] || v > upper_[c])) {
      warnings.push_back("joint " + quoted(names[i]) + " = " + number(v) + " is outside its limits [" +
                         number(lower_[c]) + ", " + number(upper_[c]) + "]");
    }
    state[c] = v;
  }
}

std::vector<double> neutral_state(const RobotModel& model) {
  std::vector<double> state(model.variable_count(), 0.0);
  for (const RobotJoint& joint : model.joints()) {
    if (joint.variable >= 0 && joint.bounded) state[joint.variable] = std::clamp(0.0, joint.lower, joint.upper);
  }
  return state;
}

std::string join_warnings(const std::vector<std::string>& warnings, std::size_t max) {
  std::string out;
  for (std::size_t i = 0; i < warnings.size() && i < max; ++i) out += (i ? "; " : "") + warnings[i];
  if (warnings.size() > max) out += "; and " + std::to_string(warnings.size() - max) + " more";
  return out;
}

namespace {

Transform rigid_from(double x, double y, double z, double qx, double qy, double qz, double qw) {
  const Eigen::Vector4d q(qx, qy, qz, qw);
  if (!q.allFinite() || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
    throw RequestError("pose has a NaN or infinite value");
  }
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    throw RequestError("pose orientation is not a unit quaternion (norm " + number(q.norm()) + ")");
  }
  const Eigen::Quaterniond rotation(qw, qx, qy, qz);
  return {rotation.normalized().toRotationMatrix(), Vec3(x, y, z)};
}

}  // namespace

Transform to_transform(const geometry_msgs::Pose& p) {
  return rigid_from(p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z,
                    p.orientation.w);
}

Transform to_transform(const geometry_msgs::Transform& t) {
  return rigid_from(t.translation.x, t.translation.y, t.translation.z, t.rotation.x, t.rotation.y, t.rotation.z,
                    t.rotation.w);
}

geometry_msgs::Pose to_pose_msg(const Transform& transform) {
  geometry_msgs::Pose p;
  p.position.x = transform.t.x();
  p.position.y = transform.t.y();
  p.position.z = transform.t.z();
  const Eigen::Quaterniond q(transform.R);
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  p.orientation.w = q.w();
  return p;
}

namespace {

void expect_dimensions(const shape_msgs::SolidPrimitive& shape, std::size_t n, const char* what, const char* names) {
  if (shape.dimensions.size() != n) {
    throw RequestError(std::string(what) + " needs " + std::to_string(n) + " dimensions (" + names + "), got " +
                       std::to_string(shape.dimensions.size()));
  }
  for (double d : shape.dimensions) {
    if (!std::isfinite(d) || d <= 0.0) {
      throw RequestError(std::string(what) + " dimensions must be positive and finite, got " + number(d));
    }
  }
}

// A pose per shape: the request's arrays must pair up.
void expect_poses(std::size_t shapes, std::size_t poses, const char* what) {
  if (shapes != poses) {
    throw RequestError(std::string(what) + ": " + std::to_string(shapes) + " shapes but " + std::to_string(poses) +
                       " poses (one pose per shape)");
  }
}

}  // namespace

ObjectShape to_object_shape(const shape_msgs::SolidPrimitive& shape) {
  using P = shape_msgs::SolidPrimitive;
  switch (shape.type) {
    case P::BOX:
      expect_dimensions(shape, 3, "BOX", "x, y, z");
      return ObjectShape::box(Vec3(shape.dimensions[P::BOX_X], shape.dimensions[P::BOX_Y], shape.dimensions[P::BOX_Z]));
    case P::SPHERE:
      expect_dimensions(shape, 1, "SPHERE", "radius");
      return ObjectShape::sphere(shape.dimensions[P::SPHERE_RADIUS]);
    case P::CYLINDER:
      expect_dimensions(shape, 2, "CYLINDER", "height, radius");
      return ObjectShape::cylinder(shape.dimensions[P::CYLINDER_RADIUS], shape.dimensions[P::CYLINDER_HEIGHT]);
    case P::CONE:
      expect_dimensions(shape, 2, "CONE", "height, radius");
      return ObjectShape::cone(shape.dimensions[P::CONE_RADIUS], shape.dimensions[P::CONE_HEIGHT]);
    default:
      throw RequestError("unknown solid primitive type " + std::to_string(int(shape.type)) +
                         " (BOX=1, SPHERE=2, CYLINDER=3, CONE=4)");
  }
}

ObjectShape to_object_shape(const shape_msgs::Mesh& shape) {
  if (shape.triangles.empty()) throw RequestError("a mesh needs at least one triangle");
  TriangleMesh mesh;
  for (const auto& v : shape.vertices) mesh.vertices.emplace_back(v.x, v.y, v.z);
  for (const shape_msgs::MeshTriangle& triangle : shape.triangles) {
    std::array<std::int32_t, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t index = triangle.vertex_indices[k];
      if (index >= mesh.vertices.size()) {
        throw RequestError("triangle vertex index " + std::to_string(index) + " is out of range (" +
                           std::to_string(mesh.vertices.size()) + " vertices)");
      }
      t[k] = static_cast<std::int32_t>(index);
    }
    mesh.triangles.push_back(t);
  }
  return ObjectShape::triangles(std::move(mesh));
}

ObjectShape mesh_resource_shape(const std::string& uri, const geometry_msgs::Vector3& scale_msg,
                                const PackageResolver& resolver) {
  if (uri.empty()) throw RequestError("a mesh resource is empty");
  Vec3 scale(scale_msg.x, scale_msg.y, scale_msg.z);
  if (scale.isZero(0.0)) scale = Vec3::Ones();
  if (!scale.allFinite() || (scale.array() == 0.0).any()) {
    throw RequestError("mesh scale must be finite and non-zero on every axis");
  }
  try {
    return ObjectShape::triangles(load_mesh(resolver.resolve(uri), scale));
  } catch (const std::exception& e) {  // MeshLoadError, or invalid_argument from resolve()
    throw RequestError("mesh " + quoted(uri) + ": " + e.what());
  }
}

std::vector<PlacedShape> object_shapes(const SetCollisionObject::Request& req, const PackageResolver& resolver) {
  expect_poses(req.primitives.size(), req.primitive_poses.size(), "primitives");
  expect_poses(req.meshes.size(), req.mesh_poses.size(), "meshes");
  expect_poses(req.mesh_resources.size(), req.mesh_resource_poses.size(), "mesh_resources");
  if (!req.mesh_resource_scales.empty() && req.mesh_resource_scales.size() != req.mesh_resources.size()) {
    throw RequestError("mesh_resource_scales holds " + std::to_string(req.mesh_resource_scales.size()) +
                       " scales for " + std::to_string(req.mesh_resources.size()) + " mesh resources (none, or one each)");
  }
  std::vector<PlacedShape> out;
  // Each shape's own error names it: "primitives[1]: CONE needs ...".
  auto add = [&](const std::string& which, auto&& make, const geometry_msgs::Pose& pose) {
    try {
      out.push_back({make(), to_transform(pose)});
    } catch (const RequestError& e) {
      throw RequestError(which + ": " + e.what());
    }
  };
  for (std::size_t i = 0; i < req.primitives.size(); ++i) {
    add("primitives[" + std::to_string(i) + "]", [&] { return to_object_shape(req.primitives[i]); }, req.primitive_poses[i]);
  }
  for (std::size_t i = 0; i < req.meshes.size(); ++i) {
    add("meshes[" + std::to_string(i) + "]", [&] { return to_object_shape(req.meshes[i]); }, req.mesh_poses[i]);
  }
  const geometry_msgs::Vector3 unit_scale;
  for (std::size_t i = 0; i < req.mesh_resources.size(); ++i) {
    const auto& scale = req.mesh_resource_scales.empty() ? unit_scale : req.mesh_resource_scales[i];
    add("mesh_resources[" + std::to_string(i) + "]",
        [&] { return mesh_resource_shape(req.mesh_resources[i], scale, resolver); }, req.mesh_resource_poses[i]);
  }
  if (out.empty()) throw RequestError("the object has no shape (primitives, meshes and mesh_resources are all empty)");
  return out;
}

namespace {

struct CoordinateField {
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
};

CoordinateField find_field(const sensor_msgs::PointCloud2& cloud, const char* name) {
  for (const auto& f : cloud.fields) {
    if (f.name != name) continue;
    if (f.datatype != sensor_msgs::PointField::FLOAT32 && f.datatype != sensor_msgs::PointField::FLOAT64) {
      throw RequestError(std::string("cloud field '") + name + "' is not FLOAT32 or FLOAT64 (datatype " +
                         std::to_string(int(f.datatype)) + ")");
    }
    const std::uint32_t bytes = f.datatype == sensor_msgs::PointField::FLOAT32 ? 4 : 8;
    if (std::uint64_t(f.offset) + bytes > cloud.point_step) {
      throw RequestError(std::string("cloud field '") + name + "' lies beyond point_step " +
                         std::to_string(cloud.point_step));
    }
    return {f.offset, f.datatype};
  }
  throw RequestError(std::string("cloud has no field '") + name + "'");
}

float read_coordinate(const std::uint8_t* point, const CoordinateField& f) {
  if (f.datatype == sensor_msgs::PointField::FLOAT32) {
    float v;
    std::memcpy(&v, point + f.offset, sizeof v);
    return v;
  }
  double v;
  std::memcpy(&v, point + f.offset, sizeof v);
  return static_cast<float>(v);
}

}  // namespace

std::vector<ScanPoint> cloud_points(const sensor_msgs::PointCloud2& cloud) {
  if (cloud.is_bigendian) throw RequestError("big-endian clouds are not supported");
  const CoordinateField x = find_field(cloud, "x"), y = find_field(cloud, "y"), z = find_field(cloud, "z");
  const std::uint64_t row_bytes = std::uint64_t(cloud.width) * cloud.point_step;
  if (row_bytes > cloud.row_step) {
    throw RequestError("cloud row_step " + std::to_string(cloud.row_step) + " is less than width * point_step " +
                       std::to_string(row_bytes));
  }
  if (std::uint64_t(cloud.height) * cloud.row_step > cloud.data.size()) {
    throw RequestError("cloud data holds " + std::to_string(cloud.data.size()) + " bytes, height * row_step is " +
                       std::to_string(std::uint64_t(cloud.height) * cloud.row_step));
  }
  std::vector<ScanPoint> points;
  points.reserve(std::size_t(cloud.width) * cloud.height);
  for (std::uint32_t row = 0; row < cloud.height; ++row) {
    const std::uint8_t* p = cloud.data.data() + std::size_t(row) * cloud.row_step;
    for (std::uint32_t col = 0; col < cloud.width; ++col, p += cloud.point_step) {
      points.emplace_back(read_coordinate(p, x), read_coordinate(p, y), read_coordinate(p, z));
    }
  }
  return points;
}

sensor_msgs::PointCloud2 to_cloud_msg(const std::vector<ScanPoint>& points, const std::string& frame) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.frame_id = frame;
  cloud.height = 1;
  cloud.width = static_cast<std::uint32_t>(points.size());
  for (const char* name : {"x", "y", "z"}) {
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = static_cast<std::uint32_t>(4 * cloud.fields.size());
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    cloud.fields.push_back(f);
  }
  cloud.point_step = 12;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_dense = false;
  cloud.data.resize(cloud.row_step);
  for (std::size_t i = 0; i < points.size(); ++i) std::memcpy(&cloud.data[12 * i], points[i].data(), 12);
  return cloud;
}

}  // namespace bvh_collision
