// bvh_collision_check: self-collision of configurations from a file, no ROS master needed.
#include <iostream>

#include "check_tool.h"

int main(int argc, char** argv) {
  return bvh_collision::run_check_tool(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr);
}
