// The ros layer's fuzz targets: what arrives from other processes. A point cloud is decoded and
// inserted as the cloud thread does; a service request is answered by a CollisionCheckerNode
// (on the demo arm) as its service thread does. Same contract as loader_targets.h: the empty
// string when the input was refused by name or handled into something valid, else what broke.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace bvh_collision::fuzz {

// A PointCloud2 built from the bytes (height, width, fields, steps, endianness, data): decoded by
// cloud_points, then inserted into a 5 cm octree (max_range 5 m, the node's limits). Decoded: no
// more points than the data holds; inserted: every leaf finite, the counts add up. Refused:
// RequestError or LimitExceeded with a message.
std::string check_point_cloud(const std::uint8_t* data, std::size_t size);

// The first byte picks one of the node's services (check_state, check_states, check_motion,
// cast_ray, clear_environment, clear_box, set_collision_object, remove_collision_object); the rest
// fills its request field by field (bytes left after a check_motion request make a check_motions
// request with the same joint names, after a remove_collision_object request a
// set_allowed_collisions request). The service handler must return (no exception escapes it)
// with either an error message or an answer whose numbers are finite where they must be, and the
// node must still answer a plain check_state afterwards. save_octree, load_scene and save_scene
// are left out: they read or write the file the request names (load_scene's reader is
// test_scene_file's, fed every malformed form it refuses). Needs a ROS master (ROS_MASTER_URI): the node advertises its services.
std::string check_service_request(const std::uint8_t* data, std::size_t size);

}  // namespace bvh_collision::fuzz
