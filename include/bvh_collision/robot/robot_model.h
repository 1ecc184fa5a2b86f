// A robot's kinematic tree and collision geometry, loaded from a URDF model: the robot layer's
// core data, indexed by integers so that kinematics and queries never touch strings or maps.
#pragma once

#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <cstdint>
#include <vector>

#include <urdf_model/model.h>

#include "bvh_collision/geometry/mesh.h"
#include "bvh_collision/geometry/primitives.h"
#include "bvh_collision/robot/package_resolver.h"

namespace bvh_collision {

// A URDF whose geometry cannot be loaded; the message names the link, the element and the file.
class RobotLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class JointType { kFixed, kRevolute, kContinuous, kPrismatic, kFloating, kPlanar };

// One <collision> element.
struct CollisionElement {
  using Shape = ShapeKind;  // a mesh, a box, a sphere or a cylinder (URDF's)
  Shape shape = Shape::kMesh;
  Transform origin;  // the element's frame in its link's frame
  // Triangles for meshes and boxes (exact, 12 triangles); null for spheres and cylinders, which
  // stay exact primitives. Shared between elements that use the same file and scale.
  std::shared_ptr<const TriangleMesh> mesh;
  double radius = 0.0;       // sphere and cylinder
  double length = 0.0;       // cylinder, along the element's z axis
  Vec3 size = Vec3::Zero();  // box
  std::string source;        // what it came from, for messages: "mesh 'package://...'", "box"
};

struct RobotLink {
  std::string name;
  int parent_joint = -1;  // -1 for the root
  std::vector<CollisionElement> collision;
};

struct RobotJoint {
  std::string name;
  JointType type = JointType::kFixed;
  int parent_link = -1, child_link = -1;
  Transform origin;           // child frame at zero motion, in the parent link's frame
  Vec3 axis = Vec3::UnitX();  // unit axis in the joint frame
  double lower = 0.0, upper = 0.0;
  bool bounded = false;  // revolute and prismatic joints have limits
  int variable = -1;     // index in the state vector (-1: fixed, mimic, floating, planar)
  int mimic = -1;        // the joint this one follows, value = multiplier * q + offset
  double multiplier = 1.0, offset = 0.0;
};

class RobotModel {
 public:
  // Throws RobotLoadError when a mesh cannot be resolved or read, or the tree is malformed.
  static RobotModel from_urdf(const urdf::ModelInterface& urdf, const PackageResolver& resolver);

  const std::string& name() const { return name_; }
  const std::vector<RobotLink>& links() const { return links_; }
  const std::vector<RobotJoint>& joints() const { return joints_; }
  // Joints in an order where every joint comes after the joint of its parent link.
  const std::vector<int>& joint_order() const { return joint_order_; }
  int root_link() const { return root_; }
  int link_index(const std::string& name) const;
  int joint_index(const std::string& name) const;
  // Names of the state vector's entries: every revolute, continuous and prismatic joint that
  // does not mimic another, in URDF order.
  const std::vector<std::string>& variable_names() const { return variable_names_; }
  std::size_t variable_count() const { return variable_names_.size(); }
  // Distinct mesh files read (a file used by several links is read once).
  std::size_t mesh_files_read() const { return mesh_files_read_; }

  // This model with one more link, `name`, hung from link `parent` at `origin` (in the parent's
  // frame) by a fixed joint named "<name>/attached": what an object the robot carries becomes
  // (world/environment.h, AttachedBody). The link has no collision elements here (its shapes
  // are the collision model's); the state vector is unchanged. Throws std::invalid_argument for
  // a name a link or joint already has, or a parent that is not a link.
  RobotModel with_fixed_link(const std::string& name, int parent, const Transform& origin) const;

 private:
  std::string name_;
  std::vector<RobotLink> links_;
  std::vector<RobotJoint> joints_;
  std::vector<int> joint_order_;
  std::vector<std::string> variable_names_;
  int root_ = -1;
  std::size_t mesh_files_read_ = 0;

  friend class RobotModelBuilder;
};

// Whether any link has a collision element. A robot without one has nothing to check: the node
// answers every query on it with no_collision_geometry_error, and the CLI stops with it.
bool has_collision_geometry(const RobotModel& model);
std::string no_collision_geometry_error(const RobotModel& model);

// A configuration drawn uniformly within joint limits (continuous joints over [-pi, pi]).
std::vector<double> random_configuration(const RobotModel& model, std::mt19937_64& rng);

// Link poses in the root link's frame for a state vector (RobotModel::variable_names order).
// Floating and planar joints take the pose given in `free_joint_poses` (indexed by joint; empty
// or a missing entry means identity). Writes model.links().size() poses.
void forward_kinematics(const RobotModel& model, const double* state, std::vector<Transform>& link_poses,
                        const std::vector<Transform>* free_joint_poses = nullptr);

// Forward kinematics for a subset of links, precomputed for speed: only the chosen links and the
// moving joints above them are computed, fixed joints are folded into one constant transform, and
// rotations about a coordinate axis (the usual URDF axis) skip the general Rodrigues formula.
class KinematicsPlan {
 public:
  KinematicsPlan() = default;
  // `wanted[l]`: link l's pose is needed. The root is always at identity.
  KinematicsPlan(const RobotModel& model, const std::vector<bool>& wanted);

  // Writes the poses of the wanted links (and of the moving-joint links above them) into
  // `link_poses` (resized to the model's link count; other entries are left as they are).
  // Same conventions as forward_kinematics.
  void compute(const double* state, std::vector<Transform>& link_poses,
               const std::vector<Transform>* free_joint_poses = nullptr) const;
  // Only the steps at `steps[0..count)` (indices into step_list(), a parent's before its
  // children): the other links' poses are read from `link_poses` as they are (a motion that moves
  // a few joints of a large robot recomputes only the links below them). No floating joints.
  void compute_steps(const double* state, std::vector<Transform>& link_poses, const std::uint32_t* steps,
                     std::size_t count) const;
  std::size_t steps() const { return steps_.size(); }

  // One computed link: its pose is parent's * fixed * the joint's motion.
  struct Step {
    int link = -1, parent = -1;  // computed link and the computed link it hangs from
    Transform fixed;             // parent link -> joint frame, fixed joints folded in
    JointType type = JointType::kFixed;
    int axis = -1;               // 0, 1, 2: the joint axis is +-that unit vector; -1: general
    Vec3 axis_vector = Vec3::UnitX();
    int variable = -1;           // state index of the value (of the mimicked joint for mimics)
    double multiplier = 1.0, offset = 0.0;
    int joint = -1;              // for floating and planar joints
  };
  // The steps in order (a parent before its children), for code that computes the same poses
  // another way (model/proxy_batch.h); the root link is at identity.
  const std::vector<Step>& step_list() const { return steps_; }
  int root() const { return root_; }
  std::size_t link_count() const { return links_; }

 private:
  std::vector<Step> steps_;
  int root_ = 0;
  std::size_t links_ = 0;
};

}  // namespace bvh_collision
