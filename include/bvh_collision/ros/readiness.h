// Waiting for a collision_checker node: it sets ~robot (its summary, one dictionary) before any
// service, and ~ready (true) once every service is served; a client waits for ~ready and reads
// nothing it did not wait for.
#pragma once

#include <string>

#include <ros/param.h>
#include <ros/time.h>

namespace bvh_collision {

// True once `<node>/ready` is true; false when `seconds` pass first or ROS shuts down.
inline bool wait_until_ready(const std::string& node, double seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  for (;;) {
    bool ready = false;
    if (ros::param::get(node + "/ready", ready) && ready) return true;
    if (ros::WallTime::now() > deadline || !ros::ok()) return false;
    ros::WallDuration(0.05).sleep();
  }
}

}  // namespace bvh_collision
