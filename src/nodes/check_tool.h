// The bvh_collision_check command-line tool, as a function: parses arguments, loads the robot,
// checks every configuration of a states file and prints one line per configuration.
//
//   bvh_collision_check --urdf FILE [--srdf FILE] [--package-path DIRS] --states FILE
//                       [--scene FILE] [--distance] [--tolerance M] [--padding M] [--print-acm]
//                       [--sample-acm N [--acm-cache FILE]]
//
// States file: first line `joints: NAME NAME ...`, then one configuration per line, values in
// that order (blank lines and lines starting with '#' ignored). Joints not named sit at 0,
// clamped into their limits. Output: `INDEX free` or `INDEX collision A:B,C:D` (0-based index,
// names sorted within and across pairs), followed with --distance by ` distance=D pair=A:B`.
// --scene FILE (MoveIt .scene text, or PlanningScene YAML when it ends in .yaml or .yml;
// io/scene_file.h) also checks each configuration against the scene's objects: a link
// touching one adds `LINK:OBJECT` to the pairs (an object of several shapes as `id#k`), and the
// distance is the nearest of either kind. A YAML scene's robot state sets the joints the states
// file leaves out; its allowed-collision entries that name an object are applied, those for two
// links are not (a warning says so).
// --print-acm first prints `check A:B` or `skip A:B REASON` for every pair of links with
// geometry. --sample-acm N also skips pairs that N random configurations show never or always
// colliding, read from --acm-cache FILE when it holds them for this URDF, SRDF and N (and
// written there otherwise). Errors go to `err`; the return value is the process exit code.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace bvh_collision {

int run_check_tool(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace bvh_collision
