#include <cmath>
#include <optional>
#include <stdexcept>

#include "bvh_collision/octree/scan.h"
#include "bvh_collision/ros/conversions.h"
#include "byte_reader.h"
#include "message_targets.h"

namespace bvh_collision {
namespace fuzz {

namespace {

const std::vector<std::string> kCloudFields = {"x", "y", "z", "rgb", "intensity", "x"};

// An organized cloud's rays with no return, as the node casts them under ~clear_no_return: the
// camera fitted to the cloud, its NaN pixels' rays clipped to a workspace.
std::string no_return_problem(const std::vector<ScanPoint>& points, std::size_t width, std::size_t height) {
  const std::optional<PinholeCamera> camera = fit_pinhole(points, width, height);
  if (!camera) return "";
  if (!camera->valid()) return "a fitted camera is not valid";
  const std::vector<ScanPoint> ends = no_return_ends(points, width, height, *camera, 5.0);
  if (ends.size() > points.size()) return "more rays with no return than pixels";
  Octree tree(0.05);
  ScanOptions options;
  options.max_range = 5.0;
  options.threads = 1;
  options.workspace = ScanWorkspace{ScanPoint::Constant(-2.0f), ScanPoint::Constant(2.0f)};
  options.clip_rays_to_workspace = true;
  const ScanStats stats = insert_scan(tree, {}, ends, ScanPoint::Zero(), options);
  if (stats.occupied != 0) return "rays with no return marked a voxel occupied";
  if (stats.skipped_invalid != 0) return "a ray with no return was not finite";
  return "";
}

std::string cloud_problem(const std::vector<ScanPoint>& points, std::size_t data_bytes) {
  if (points.size() > data_bytes / 4) return "decoded more points than the data holds";
  Octree tree(0.05);
  ScanOptions options;
  options.max_range = 5.0;
  options.threads = 1;
  const ScanStats stats = insert_scan(tree, points, ScanPoint::Zero(), options);
  if (stats.points != points.size()) return "insertion counted another number of points";
  if (stats.skipped_invalid + stats.skipped_outside + stats.skipped_workspace > stats.points) {
    return "insertion skipped more points than it was given";
  }
  for (const Octree::Leaf& leaf : tree.leaves()) {
    if (!std::isfinite(leaf.log_odds)) return "a leaf value is not finite after insertion";
  }
  return "";
}

}  // namespace

std::string check_point_cloud(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  sensor_msgs::PointCloud2 cloud;
  cloud.height = in.byte() < 200 ? in.count(4) : in.u32();
  cloud.width = in.byte() < 200 ? in.count(64) : in.u32();
  cloud.fields.resize(in.count(5));
  for (auto& f : cloud.fields) {
    f.name = in.name(kCloudFields);
    f.offset = in.byte() < 240 ? in.count(40) : in.u32();
    f.datatype = in.count(9);
    f.count = in.count(3);
  }
  cloud.is_bigendian = in.byte() == 255;
  cloud.point_step = in.byte() < 200 ? in.count(48) : in.u32();
  cloud.row_step = in.byte() < 128 ? cloud.point_step * cloud.width : in.u32();
  cloud.data = in.rest();
  try {
    Limits limits;
    check_limit("a cloud with its points", double(cloud.width) * double(cloud.height), limits.cloud_points, "max_cloud_points");
    const std::vector<ScanPoint> points = cloud_points(cloud);
    const std::string problem = cloud_problem(points, cloud.data.size());
    return problem.empty() ? no_return_problem(points, cloud.width, cloud.height) : problem;
  } catch (const std::invalid_argument& e) {  // RequestError, LimitExceeded
    return *e.what() ? "" : "refused without a message";
  }
}

}  // namespace fuzz
}  // namespace bvh_collision
