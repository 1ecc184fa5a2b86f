#include <algorithm>
#include "bvh_collision/robot/robot_model.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>

#include "bvh_collision/geometry/sin_cos.h"
#include "bvh_collision/geometry/split_column.h"
#include "bvh_collision/robot/mesh_loader.h"
#include "bvh_collision/robot/urdf_validation.h"

namespace bvh_collision {
namespace {

Transform to_transform(const urdf::Pose& p) {
  const Eigen::Quaterniond q(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  return {q.normalized().toRotationMatrix(), Vec3(p.position.x, p.position.y, p.position.z)};
}

JointType joint_type(int t) {
  switch (t) {
    case urdf::Joint::REVOLUTE: return JointType::kRevolute;
    case urdf::Joint::CONTINUOUS: return JointType::kContinuous;
    case urdf::Joint::PRISMATIC: return JointType::kPrismatic;
    case urdf::Joint::FLOATING: return JointType::kFloating;
    case urdf::Joint::PLANAR: return JointType::kPlanar;
    default: return JointType::kFixed;
  }
}

}  // namespace

class RobotModelBuilder {
 public:
  RobotModelBuilder(const urdf::ModelInterface& urdf, const PackageResolver& resolver)
      : urdf_(urdf), resolver_(resolver) {}

  RobotModel build() {
    model_.name_ = urdf_.getName();
    if (!urdf_.getRoot()) throw RobotLoadError("robot '" + model_.name_ + "' has no root link");
    add_link(*urdf_.getRoot(), -1);
    model_.root_ = 0;
    assign_variables_and_mimics();
    return std::move(model_);
  }

 private:
  // Depth-first from the root: links and joints get indices in tree order, so the joint order
  // (parents first) is simply the order of creation.
  void add_link(const urdf::Link& link, int parent_joint) {
    const int index = static_cast<int>(model_.links_.size());
    model_.links_.push_back({link.name, parent_joint, {}});
    link_index_[link.name] = index;
    for (std::size_t e = 0; e < link.collision_array.size(); ++e) {
      if (link.collision_array[e] && link.collision_array[e]->geometry) {
        model_.links_[index].collision.push_back(load_element(link.name, e, *link.collision_array[e]));
      }
    }
    for (const auto& joint : link.child_joints) {
      const urdf::LinkConstSharedPtr child = urdf_.getLink(joint->child_link_name);
      if (!child) throw RobotLoadError("joint '" + joint->name + "' names a missing child link '" + joint->child_link_name + "'");
      const int j = static_cast<int>(model_.joints_.size());
      RobotJoint rj;
      rj.name = joint->name;
      rj.type = joint_type(joint->type);
      rj.parent_link = index;
      rj.origin = to_transform(joint->parent_to_joint_origin_transform);
      const Vec3 axis(joint->axis.x, joint->axis.y, joint->axis.z);
      rj.axis = axis.norm() > 0 ? Vec3(axis.normalized()) : Vec3(Vec3::UnitX());
      if (joint->limits && (rj.type == JointType::kRevolute || rj.type == JointType::kPrismatic)) {
        rj.lower = joint->limits->lower;
        rj.upper = joint->limits->upper;
        rj.bounded = true;
      }
      model_.joints_.push_back(rj);
      model_.joint_order_.push_back(j);
      mimic_source_[j] = joint->mimic;
      add_link(*child, j);
      model_.joints_[j].child_link = link_index_.at(child->name);
    }
  }

  void assign_variables_and_mimics() {
    for (std::size_t j = 0; j < model_.joints_.size(); ++j) {
      RobotJoint& joint = model_.joints_[j];
      const auto& mimic = mimic_source_[static_cast<int>(j)];
      const bool moves = joint.type == JointType::kRevolute || joint.type == JointType::kContinuous ||
                         joint.type == JointType::kPrismatic;
      if (!moves) continue;
      if (mimic) {
        joint.mimic = model_.joint_index(mimic->joint_name);
        if (joint.mimic < 0) throw RobotLoadError("joint '" + joint.name + "' mimics unknown joint '" + mimic->joint_name + "'");
        joint.multiplier = mimic->multiplier;
        joint.offset = mimic->offset;
        continue;
      }
      joint.variable = static_cast<int>(model_.variable_names_.size());
      model_.variable_names_.push_back(joint.name);
    }
    // A chain of mimics resolves to a joint with a variable.
    for (RobotJoint& joint : model_.joints_) {
      for (int hops = 0; joint.mimic >= 0 && model_.joints_[joint.mimic].mimic >= 0; ++hops) {
        if (hops > 64) throw RobotLoadError("joint '" + joint.name + "': mimic cycle");
        const RobotJoint& via = model_.joints_[joint.mimic];
        joint.offset = joint.multiplier * via.offset + joint.offset;
        joint.multiplier *= via.multiplier;
        joint.mimic = via.mimic;
      }
      if (joint.mimic >= 0 && model_.joints_[joint.mimic].variable < 0) {
        throw RobotLoadError("joint '" + joint.name + "' mimics joint '" + model_.joints_[joint.mimic].name +
                             "', which does not move");
      }
    }
  }

  CollisionElement load_element(const std::string& link, std::size_t element, const urdf::Collision& c) {
    CollisionElement out;
    out.origin = to_transform(c.origin);
    const urdf::Geometry& g = *c.geometry;
    std::ostringstream where;
    where << "link '" << link << "', collision element " << element + 1;
    switch (g.type) {
      case urdf::Geometry::BOX: {
        const auto& b = static_cast<const urdf::Box&>(g);
        out.shape = CollisionElement::Shape::kBox;
        out.size = Vec3(b.dim.x, b.dim.y, b.dim.z);
        if (!(out.size.array() > 0).all()) throw RobotLoadError(where.str() + ": box size must be positive");
        out.mesh = std::make_shared<TriangleMesh>(box_mesh(out.size));
        out.source = "box";
        break;
      }
      case urdf::Geometry::SPHERE: {
        out.shape = CollisionElement::Shape::kSphere;
        out.radius = static_cast<const urdf::Sphere&>(g).radius;
        if (!(out.radius > 0)) throw RobotLoadError(where.str() + ": sphere radius must be positive");
        out.source = "sphere";
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& cy = static_cast<const urdf::Cylinder&>(g);
        out.shape = CollisionElement::Shape::kCylinder;
        out.radius = cy.radius;
        out.length = cy.length;
        if (!(out.radius > 0 && out.length > 0)) throw RobotLoadError(where.str() + ": cylinder radius and length must be positive");
        out.source = "cylinder";  // exact: no polygon stands in for it
        break;
      }
      case urdf::Geometry::MESH: {
        const auto& m = static_cast<const urdf::Mesh&>(g);
        out.shape = CollisionElement::Shape::kMesh;
        out.source = "mesh '" + m.filename + "'";
        out.mesh = load_mesh_once(where.str(), m.filename, Vec3(m.scale.x, m.scale.y, m.scale.z));
        break;
      }
    }
    return out;
  }

  std::shared_ptr<const TriangleMesh> load_mesh_once(const std::string& where, const std::string& uri, const Vec3& scale) {
    std::string path;
    try {
      path = resolver_.resolve(uri);
    } catch (const std::invalid_argument& e) {
      throw RobotLoadError(where + ": mesh '" + uri + "': " + e.what());
    }
    const auto key = std::make_tuple(path, scale.x(), scale.y(), scale.z());
    if (const auto it = scaled_.find(key); it != scaled_.end()) return it->second;
    auto& unscaled = files_[path];
    try {
      if (!unscaled) {
        unscaled = std::make_shared<TriangleMesh>(load_mesh(path));
        ++model_.mesh_files_read_;
      }
    } catch (const MeshLoadError& e) {
      throw RobotLoadError(where + ": mesh '" + uri + "': " + e.what());
    }
    if (!scale.allFinite() || (scale.array() == 0.0).any()) {
      throw RobotLoadError(where + ": mesh '" + uri + "': scale must be finite and non-zero");
    }
    auto mesh = std::make_shared<TriangleMesh>(*unscaled);
    for (std::size_t i = 0; i < mesh->vertices.size(); ++i) {
      Vec3& v = mesh->vertices[i];
      v = v.cwiseProduct(scale);
      if (!v.allFinite() || v.cwiseAbs().maxCoeff() > kMaxCoordinate) {
        throw RobotLoadError(where + ": mesh '" + uri + "': vertex " + std::to_string(i) + " scaled lies beyond " +
                             std::to_string(static_cast<long>(kMaxCoordinate)) + " m");
      }
    }
    if (scale.x() * scale.y() * scale.z() < 0.0) {
      for (auto& t : mesh->triangles) std::swap(t[1], t[2]);  // mirrored: keep outward winding
    }
    return scaled_[key] = mesh;
  }

  const urdf::ModelInterface& urdf_;
  const PackageResolver& resolver_;
  RobotModel model_;
  std::map<std::string, int> link_index_;
  std::map<int, urdf::JointMimicSharedPtr> mimic_source_;
  std::map<std::string, std::shared_ptr<TriangleMesh>> files_;
  std::map<std::tuple<std::string, double, double, double>, std::shared_ptr<const TriangleMesh>> scaled_;
};

RobotModel RobotModel::from_urdf(const urdf::ModelInterface& urdf, const PackageResolver& resolver) {
  return RobotModelBuilder(urdf, resolver).build();
}

RobotModel RobotModel::with_fixed_link(const std::string& name, int parent, const Transform& origin) const {
  if (parent < 0 || parent >= static_cast<int>(links_.size())) {
    throw std::invalid_argument("link '" + name + "': no parent link " + std::to_string(parent));
  }
  const std::string joint_name = name + "/attached";
  if (name.empty() || link_index(name) >= 0 || joint_index(joint_name) >= 0) {
    throw std::invalid_argument("link '" + name + "': the robot already has a link or joint of that name");
  }
  RobotModel out = *this;
  RobotJoint joint;
  joint.name = joint_name;
  joint.type = JointType::kFixed;
  joint.parent_link = parent;
  joint.child_link = static_cast<int>(links_.size());
  joint.origin = origin;
  out.joint_order_.push_back(static_cast<int>(out.joints_.size()));
  out.joints_.push_back(joint);
  out.links_.push_back({name, static_cast<int>(out.joints_.size()) - 1, {}});
  return out;
}

int RobotModel::link_index(const std::string& name) const {
  for (std::size_t i = 0; i < links_.size(); ++i) {
    if (links_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

int RobotModel::joint_index(const std::string& name) const {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    if (joints_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

namespace {

// Products of poses written out as split columns (geometry/split_column.h).
// out.t = a.R b.t + a.t, from a's columns.
[[gnu::always_inline]] inline void translate(const SplitColumn* a, const Transform& at, const Transform& b, Transform& out) {
  SplitColumn t = times(a, b.t.data());
  const SplitColumn p = load_column(at.t.data());
  t.top += p.top;
  t.bottom += p.bottom;
  store_column(t, out.t.data());
}

// out = a * b. `out` must not be `a` or `b`.
[[gnu::always_inline]] inline void compose_into(const Transform& a, const Transform& b, Transform& out) {
  SplitColumn p[3];
  load_rotation(a.R, p);
  for (int c = 0; c < 3; ++c) store_column(times(p, b.R.col(c).data()), out.R.col(c).data());
  translate(p, a, b, out);
}

inline Transform compose(const Transform& a, const Transform& b) {
  Transform out;
  compose_into(a, b, out);
  return out;
}

// Rotation by angle q about unit axis k (Rodrigues).
inline Mat3 axis_rotation(const Vec3& k, double q) {
  const double c = std::cos(q), s = std::sin(q), v = 1.0 - c;
  Mat3 r;
  r << c + k.x() * k.x() * v, k.x() * k.y() * v - k.z() * s, k.x() * k.z() * v + k.y() * s,
       k.y() * k.x() * v + k.z() * s, c + k.y() * k.y() * v, k.y() * k.z() * v - k.x() * s,
       k.z() * k.x() * v - k.y() * s, k.z() * k.y() * v + k.x() * s, c + k.z() * k.z() * v;
  return r;
}

}  // namespace

bool has_collision_geometry(const RobotModel& model) {
  return std::any_of(model.links().begin(), model.links().end(), [](const RobotLink& l) { return !l.collision.empty(); });
}

std::string no_collision_geometry_error(const RobotModel& model) {
  return "robot '" + model.name() + "' has no collision geometry: there is nothing to check";
}

std::vector<double> random_configuration(const RobotModel& model, std::mt19937_64& rng) {
  std::vector<double> q(model.variable_count());
  for (std::size_t v = 0; v < q.size(); ++v) {
    const RobotJoint& j = model.joints()[model.joint_index(model.variable_names()[v])];
    q[v] = std::uniform_real_distribution<double>(j.bounded ? j.lower : -M_PI, j.bounded ? j.upper : M_PI)(rng);
  }
  return q;
}

void forward_kinematics(const RobotModel& model, const double* state, std::vector<Transform>& poses,
                        const std::vector<Transform>* free_joint_poses) {
  poses.resize(model.links().size());
  poses[model.root_link()] = Transform();
  for (const int j : model.joint_order()) {
    const RobotJoint& joint = model.joints()[j];
    const Transform base = compose(poses[joint.parent_link], joint.origin);
    double q = 0.0;
    if (joint.variable >= 0) {
      q = state[joint.variable];
    } else if (joint.mimic >= 0) {
      q = joint.multiplier * state[model.joints()[joint.mimic].variable] + joint.offset;
    }
    Transform& child = poses[joint.child_link];
    switch (joint.type) {
      case JointType::kRevolute:
      case JointType::kContinuous:
        child = compose(base, Transform{axis_rotation(joint.axis, q), Vec3::Zero()});
        break;
      case JointType::kPrismatic: {
        const Vec3 d = q * joint.axis;
        child = base;
        for (int i = 0; i < 3; ++i) child.t[i] += base.R(i, 0) * d[0] + base.R(i, 1) * d[1] + base.R(i, 2) * d[2];
        break;
      }
      case JointType::kFloating:
      case JointType::kPlanar:
        child = (free_joint_poses != nullptr && static_cast<std::size_t>(j) < free_joint_poses->size())
                    ? compose(base, (*free_joint_poses)[j])
                    : base;
        break;
      case JointType::kFixed:
        child = base;
        break;
    }
  }
}

KinematicsPlan::KinematicsPlan(const RobotModel& model, const std::vector<bool>& wanted)
    : root_(model.root_link()), links_(model.links().size()) {
  // A link is needed if it is wanted or some needed link hangs below it.
  std::vector<bool> needed(links_, false);
  for (std::size_t l = 0; l < links_ && l < wanted.size(); ++l) needed[l] = wanted[l];
  const auto& order = model.joint_order();
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    const RobotJoint& j = model.joints()[*it];
    if (needed[j.child_link]) needed[j.parent_link] = true;
  }
  // Each link's nearest computed ancestor (anchor) and the constant transform from it.
  std::vector<int> anchor(links_, -1);
  std::vector<Transform> from_anchor(links_);
  anchor[root_] = root_;
  for (const int ji : order) {
    const RobotJoint& j = model.joints()[ji];
    if (!needed[j.child_link]) continue;
    const int p = j.parent_link, c = j.child_link;
    Step step;
    step.link = c;
    step.parent = anchor[p];
    step.fixed = compose(from_anchor[p], j.origin);
    step.type = j.type;
    if (j.type == JointType::kFixed && !(c < static_cast<int>(wanted.size()) && wanted[c])) {
      anchor[c] = anchor[p];  // an intermediate frame: folded into its children's steps
      from_anchor[c] = step.fixed;
      continue;
    }
    step.axis_vector = j.axis;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(j.axis[k]) == 1.0 && j.axis[(k + 1) % 3] == 0.0 && j.axis[(k + 2) % 3] == 0.0) step.axis = k;
    }
    step.variable = j.variable >= 0 ? j.variable : (j.mimic >= 0 ? model.joints()[j.mimic].variable : -1);
    step.multiplier = j.variable >= 0 ? 1.0 : j.multiplier;
    step.offset = j.variable >= 0 ? 0.0 : j.offset;
    step.joint = ji;
    steps_.push_back(step);
    anchor[c] = c;
    from_anchor[c] = Transform();
  }
}

namespace {

// parent * fixed * (rotation about +-unit axis K with cosine c and sine s, the sign applied):
// the rotation mixes only two columns of parent * fixed, mixed here as they are computed rather
// than stored and read back, two rows at a time (the same operations on each value as the
// product then the rotation: the same bits, test KinematicsPlan.StepsEqualTheScalarProducts...;
// a third fewer instructions a pose: docs/performance.md).
template <int K>
void compose_axis_rotation(const Transform& parent, const Transform& fixed, double c, double s, Transform& out) {
  constexpr int i = (K + 1) % 3, j = (K + 2) % 3;  // R_K(q) maps e_i -> c e_i + s e_j, e_j -> -s e_i + c e_j
  SplitColumn p[3];
  load_rotation(parent.R, p);
  const SplitColumn a = times(p, fixed.R.col(i).data()), b = times(p, fixed.R.col(j).data());
  store_column(times(p, fixed.R.col(K).data()), out.R.col(K).data());
  store_column({c * a.top + s * b.top, c * a.bottom + s * b.bottom}, out.R.col(i).data());
  store_column({c * b.top - s * a.top, c * b.bottom - s * a.bottom}, out.R.col(j).data());
  translate(p, parent, fixed, out);
}

void compose_axis_rotation(const Transform& parent, const Transform& fixed, int k, double c, double s, Transform& out) {
  switch (k) {
    case 0: return compose_axis_rotation<0>(parent, fixed, c, s, out);
    case 1: return compose_axis_rotation<1>(parent, fixed, c, s, out);
    default: return compose_axis_rotation<2>(parent, fixed, c, s, out);
  }
}

bool about_unit_axis(const KinematicsPlan::Step& step) {
  return (step.type == JointType::kRevolute || step.type == JointType::kContinuous) && step.axis >= 0;
}

// The sines and cosines of the steps at `index[0..count)` (`index` null: steps [first, first +
// count)) that rotate about a unit axis, before the chain of products that needs them:
// independent of one another, they overlap in the processor instead of waiting on each parent's
// pose.
void step_sin_cos(const std::vector<KinematicsPlan::Step>& steps, const std::uint32_t* index, std::size_t first,
                  std::size_t count, const double* state, double* s, double* c) {
  for (std::size_t i = 0; i < count; ++i) {
    const KinematicsPlan::Step& step = steps[index != nullptr ? index[i] : first + i];
    if (!about_unit_axis(step)) continue;
    sin_cos(step.multiplier * state[step.variable] + step.offset, s[i], c[i]);
    s[i] *= step.axis_vector[step.axis];
  }
}

// One step: the child's pose from its parent's (sine and cosine given for a unit axis).
inline void compute_step(const KinematicsPlan::Step& step, const double* state, double sine, double cosine,
                         std::vector<Transform>& poses, const std::vector<Transform>* free_joint_poses) {
  const double q = step.variable >= 0 ? step.multiplier * state[step.variable] + step.offset : 0.0;
  const Transform& parent = poses[step.parent];
  Transform& child = poses[step.link];
  switch (step.type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
      if (step.axis >= 0) {
        compose_axis_rotation(parent, step.fixed, step.axis, cosine, sine, child);
      } else {
        child = compose(compose(parent, step.fixed), Transform{axis_rotation(step.axis_vector, q), Vec3::Zero()});
      }
      break;
    case JointType::kPrismatic:
      compose_into(parent, step.fixed, child);
      child.t += child.R * (q * step.axis_vector);
      break;
    case JointType::kFloating:
    case JointType::kPlanar: {
      const bool given = free_joint_poses != nullptr && static_cast<std::size_t>(step.joint) < free_joint_poses->size();
      child = given ? compose(compose(parent, step.fixed), (*free_joint_poses)[step.joint]) : compose(parent, step.fixed);
      break;
    }
    case JointType::kFixed:
      compose_into(parent, step.fixed, child);
      break;
  }
}

}  // namespace

// Built twice, the CPU choosing at load time: with AVX's three-operand forms the split columns
// need no register copies (docs/performance.md), and no fused
// multiply-add is enabled, so both give the same bits. Flattened: a clone inlines only what it
// is given. (clang 14, make fuzz's compiler, names its dispatcher apart from the function,
// which its callers then miss at link time: one build there.)
#if defined(__clang__)
#define BVH_KINEMATICS_BUILDS flatten
#else
#define BVH_KINEMATICS_BUILDS target_clones("avx2", "default"), flatten
#endif
__attribute__((BVH_KINEMATICS_BUILDS)) void KinematicsPlan::compute(const double* state, std::vector<Transform>& poses,
                             const std::vector<Transform>* free_joint_poses) const {
  poses.resize(links_);
  poses[root_] = Transform();
  constexpr std::size_t kBlock = 32;  // steps per block of sines and cosines (on the stack)
  double sines[kBlock], cosines[kBlock];
  for (std::size_t first = 0; first < steps_.size(); first += kBlock) {
    const std::size_t count = std::min(kBlock, steps_.size() - first);
    step_sin_cos(steps_, nullptr, first, count, state, sines, cosines);
    for (std::size_t i = 0; i < count; ++i) compute_step(steps_[first + i], state, sines[i], cosines[i], poses, free_joint_poses);
  }
}

__attribute__((BVH_KINEMATICS_BUILDS)) void KinematicsPlan::compute_steps(const double* state, std::vector<Transform>& poses,
                                                                        const std::uint32_t* steps, std::size_t count) const {
  constexpr std::size_t kBlock = 32;
  double sines[kBlock], cosines[kBlock];
  for (std::size_t first = 0; first < count; first += kBlock) {
    const std::size_t n = std::min(kBlock, count - first);
    step_sin_cos(steps_, steps + first, 0, n, state, sines, cosines);
    for (std::size_t i = 0; i < n; ++i) compute_step(steps_[steps[first + i]], state, sines[i], cosines[i], poses, nullptr);
  }
}

}  // namespace bvh_collision
