#include "check_tool.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "bvh_collision/query/acm_sampling.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/robot/link_solidity.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/robot/urdf_validation.h"
#include "bvh_collision/session/scene_frames.h"

namespace bvh_collision {
namespace {

constexpr const char* kUsage =
    "usage: bvh_collision_check --urdf FILE [--srdf FILE] [--package-path DIRS] --states FILE\n"
    "                           [--scene FILE] [--distance] [--tolerance M] [--padding M]\n"
    "                           [--print-acm] [--sample-acm N [--acm-cache FILE]] [--help]\n"
    "\n"
    "Checks every configuration of a states file for collision and prints one line each:\n"
    "`INDEX free` or `INDEX collision A:B,C:D` (names sorted), with --distance ` distance=D pair=A:B`.\n"
    "\n"
    "  --urdf FILE          the robot description (required)\n"
    "  --srdf FILE          its semantic description: pairs never checked, group states\n"
    "  --package-path DIRS  ':'-separated folders where package:// mesh paths are looked up\n"
    "                       (before ROS_PACKAGE_PATH and CMAKE_PREFIX_PATH)\n"
    "  --states FILE        first line `joints: NAME ...`, then one configuration a line\n"
    "                       (required unless --print-acm)\n"
    "  --scene FILE         also check against a MoveIt .scene, or a PlanningScene in YAML\n"
    "                       (.yaml, .yml): its objects, attached objects and robot state\n"
    "  --distance           print the distance to the nearest pair (0 in collision)\n"
    "  --tolerance M        allowed error in metres (a pair closer than M may be reported)\n"
    "  --padding M          padding added to every link, in metres\n"
    "  --print-acm          print `check A:B` or `skip A:B REASON` for every pair of links\n"
    "  --sample-acm N       also skip pairs that N random configurations show never or always colliding\n"
    "  --acm-cache FILE     read the sampled pairs from FILE, or write them there\n"
    "  --help, -h           print this and exit\n";

struct Options {
  std::string urdf, srdf, states, package_path, acm_cache, scene;
  std::size_t sample_acm = 0;
  bool distance = false, print_acm = false, help = false;
  double tolerance = 0.0, padding = 0.0;
};

// The whole text as a finite decimal number, or nothing.
std::optional<double> to_number(const std::string& text) {
  const std::optional<double> v = parse_decimal(text);
  return v && std::isfinite(*v) ? v : std::nullopt;
}

double parse_number(const std::string& flag, const std::string& text) {
  const auto v = to_number(text);
  if (!v || *v < 0) throw std::invalid_argument(flag + " needs a number >= 0, got '" + text + "'");
  return *v;
}

// A whole number of samples: the text is all digits and the value within [1, kMaxSamples].
std::size_t parse_count(const std::string& flag, const std::string& text) {
  constexpr std::size_t kMaxSamples = 1000000000;
  const bool digits = !text.empty() && text.size() <= 10 && text.find_first_not_of("0123456789") == std::string::npos;
  const unsigned long long v = digits ? std::stoull(text) : 0;
  if (!digits || v < 1 || v > kMaxSamples) {
    throw std::invalid_argument(flag + " needs a whole number from 1 to " + std::to_string(kMaxSamples) + ", got '" + text + "'");
  }
  return static_cast<std::size_t>(v);
}

Options parse_args(const std::vector<std::string>& args) {
  Options o;
  auto value = [&](std::size_t& i) {
    if (i + 1 >= args.size()) throw std::invalid_argument(args[i] + " needs a value");
    return args[++i];
  };
  // Asked for anywhere, the usage answers alone: nothing else is read.
  if (std::find(args.begin(), args.end(), "--help") != args.end() || std::find(args.begin(), args.end(), "-h") != args.end()) {
    o.help = true;
    return o;
  }
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--urdf") o.urdf = value(i);
    else if (a == "--srdf") o.srdf = value(i);
    else if (a == "--states") o.states = value(i);
    else if (a == "--scene") o.scene = value(i);
    else if (a == "--package-path") o.package_path = value(i);
    else if (a == "--distance") o.distance = true;
    else if (a == "--print-acm") o.print_acm = true;
    else if (a == "--tolerance") o.tolerance = parse_number(a, value(i));
    else if (a == "--padding") o.padding = parse_number(a, value(i));
    else if (a == "--sample-acm") o.sample_acm = parse_count(a, value(i));
    else if (a == "--acm-cache") o.acm_cache = value(i);
    else throw std::invalid_argument("unknown argument '" + a + "' (--help lists them)");
  }
  if (o.urdf.empty()) throw std::invalid_argument("--urdf FILE is required");
  if (o.states.empty() && !o.print_acm) throw std::invalid_argument("--states FILE is required");
  return o;
}

// Regular files only, of bounded size (read_description_file).
std::string read_file(const std::string& path, const char* what) {
  try {
    return read_description_file(std::string(what) + " file", path);
  } catch (const RobotDescriptionError& e) {
    throw std::invalid_argument(e.what());
  }
}

std::string pair_name(const RobotModel& m, int a, int b) {
  const auto [x, y] = std::minmax(m.links()[a].name, m.links()[b].name);
  return x + ":" + y;
}

double parse_value(const std::string& path, int line, const std::string& word) {
  const auto v = to_number(word);
  if (!v) throw std::invalid_argument(path + ":" + std::to_string(line) + ": '" + word + "' is not a finite number");
  return *v;
}

// The states file: joint indices into the state vector, then rows of values.
struct States {
  std::vector<int> variables;
  std::vector<std::vector<double>> rows;
};

States read_states(const std::string& path, const RobotModel& m) {
  std::istringstream in(read_file(path, "states"));
  States s;
  std::string line;
  bool header = false;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::istringstream words(line.substr(start));
    if (!header) {
      std::string tag, name;
      words >> tag;
      if (tag != "joints:") throw std::invalid_argument(path + ":" + std::to_string(number) + ": the first line must be 'joints: NAME ...'");
      while (words >> name) {
        const int j = m.joint_index(name);
        if (j < 0 || m.joints()[j].variable < 0) {
          throw std::invalid_argument(path + ":" + std::to_string(number) + ": '" + name + "' is not a movable, non-mimic joint of the robot");
        }
        if (std::find(s.variables.begin(), s.variables.end(), m.joints()[j].variable) != s.variables.end()) {
          throw std::invalid_argument(path + ":" + std::to_string(number) + ": joint '" + name + "' is named twice");
        }
        s.variables.push_back(m.joints()[j].variable);
      }
      header = true;
      continue;
    }
    std::vector<double> row;
    std::string word;
    while (words >> word) row.push_back(parse_value(path, number, word));
    if (row.size() != s.variables.size()) {
      throw std::invalid_argument(path + ":" + std::to_string(number) + ": " + std::to_string(row.size()) + " values for " +
                                  std::to_string(s.variables.size()) + " joints");
    }
    s.rows.push_back(std::move(row));
  }
  if (!header) throw std::invalid_argument(path + ": no 'joints:' line");
  return s;
}

void print_acm(const CollisionChecker& checker, std::ostream& out) {
  const RobotModel& m = checker.model();
  std::vector<std::string> lines;
  for (std::size_t a = 0; a < m.links().size(); ++a) {
    for (std::size_t b = a + 1; b < m.links().size(); ++b) {
      if (m.links()[a].collision.empty() || m.links()[b].collision.empty()) continue;
      const std::string pair = pair_name(m, a, b);
      lines.push_back(checker.acm().allowed(a, b) ? "skip " + pair + " " + acm_reason_name(checker.acm().reason(a, b))
                                                  : "check " + pair);
    }
  }
  std::sort(lines.begin(), lines.end(), [](const std::string& x, const std::string& y) {
    return x.substr(x.find(' ')) < y.substr(y.find(' '));  // by pair name
  });
  for (const std::string& l : lines) out << l << "\n";
  // Which links are solids (a link inside one collides), and which meshes are not, and why.
  const LinkSolidity solidity = link_solidity(m);
  for (const int l : solidity.solid_links) out << "solid " << m.links()[l].name << "\n";
  for (const OpenMesh& open : solidity.open_meshes) out << "open " << describe(open, m) << "\n";
}

// Adds pairs that --sample-acm N random configurations show never or always colliding, from the
// --acm-cache file when it holds them for this URDF, SRDF and N.
AllowedCollisionMatrix with_sampled_pairs(const Options& o, const std::string& srdf_xml, const RobotModel& model,
                                          AllowedCollisionMatrix acm, const CheckerOptions& options, std::ostream& err) {
  SamplingOptions sampling;
  sampling.samples = o.sample_acm;
  const std::string key = sampling_cache_key(read_file(o.urdf, "URDF"), srdf_xml, sampling);
  SampledPairs pairs;
  if (o.acm_cache.empty() || !read_sampling_cache(o.acm_cache, key, model, pairs)) {
    pairs = sample_collision_pairs(CollisionChecker(model, acm, options), sampling);
    if (!o.acm_cache.empty() && !write_sampling_cache(o.acm_cache, key, model, pairs)) {
      err << "warning: cannot write the ACM cache '" << o.acm_cache << "'\n";
    }
  }
  apply_sampled_pairs(pairs, acm);
  return acm;
}

// A YAML scene's robot state into `state` (the joints a states file leaves out keep these); what
// it names that the robot lacks, and its entries for pairs of links (not applied: the entries
// that name an object are, by the scene's environment), are warned of.
void apply_scene_state(const SceneFile& scene, const RobotModel& m, std::vector<double>& state, std::ostream& err) {
  for (const auto& [name, value] : scene.joint_values) {
    const auto& names = m.variable_names();
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) {
      err << "warning: the scene's robot state names '" << name << "', which is not a joint variable of the robot\n";
      continue;
    }
    state[static_cast<std::size_t>(it - names.begin())] = value;
  }
  const auto link_pairs = std::count_if(scene.allowed_collisions.begin(), scene.allowed_collisions.end(), [&](const AllowedCollision& e) {
    return m.link_index(e.a) >= 0 && m.link_index(e.b) >= 0;
  });
  if (link_pairs > 0) {
    err << "warning: the scene's " << link_pairs
        << " allowed-collision entries for pairs of links are not applied (use --srdf for the robot's own pairs)\n";
  }
}

// One configuration's line: `INDEX free` or `INDEX collision A:B,...` (link pairs and, with a
// scene, link:object pairs, name-sorted), then with --distance the nearest pair of either kind.
void print_state(const Options& o, const CollisionChecker& checker, const Environment* world,
                 const std::vector<double>& state, std::size_t index, std::ostream& out) {
  const RobotModel& m = checker.model();
  SelfCollisionRequest request;
  request.all_pairs = true;
  request.distance = o.distance;
  request.tolerance = o.tolerance;
  const SelfCollisionResult r = checker.check_self(state.data(), request);
  std::vector<std::string> pairs;
  for (const auto& [a, b] : r.colliding_pairs) pairs.push_back(pair_name(m, a, b));
  bool collision = r.collision;
  double distance = r.min_distance;
  std::string nearest = r.closest_a >= 0 ? pair_name(m, r.closest_a, r.closest_b) : "-";
  if (world != nullptr) {
    EnvironmentRequest er;
    er.all_links = true;
    er.distance = o.distance;
    er.tolerance = o.tolerance;
    const EnvironmentResult e = checker.check_environment(state.data(), *world, er);
    for (const EnvironmentContact& c : e.contacts) pairs.push_back(m.links()[c.link].name + ":" + c.object);
    collision = collision || e.collision;
    if (o.distance && e.min_distance < distance && e.closest_link >= 0) {
      distance = e.min_distance;
      nearest = m.links()[e.closest_link].name + ":" + e.closest_object;
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  out << index << (collision ? " collision " : " free");
  for (std::size_t p = 0; p < pairs.size(); ++p) out << (p ? "," : "") << pairs[p];
  if (o.distance) out << " distance=" << std::setprecision(9) << (collision ? 0.0 : distance) << " pair=" << nearest;
  out << "\n";
}

}  // namespace


int run_check_tool(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  try {
    const Options o = parse_args(args);
    if (o.help) {
      out << kUsage;
      return 0;
    }
    std::vector<std::string> roots = split_path_list(o.package_path);
    if (const char* env = std::getenv("ROS_PACKAGE_PATH")) {
      for (const std::string& p : split_path_list(env)) roots.push_back(p);
    }
    const char* prefixes = std::getenv("CMAKE_PREFIX_PATH");
    RobotModel model = RobotModel::from_urdf(*load_robot_description_file(o.urdf),
                                             PackageResolver(roots, split_path_list(prefixes ? prefixes : "")));
    // As the node answers every query on such a robot: nothing to check is an error, not "free".
    if (!has_collision_geometry(model)) throw std::invalid_argument(no_collision_geometry_error(model));
    AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
    const std::string srdf_xml = o.srdf.empty() ? "" : read_file(o.srdf, "SRDF");
    if (!o.srdf.empty()) {
      const Srdf semantic = parse_srdf(srdf_xml, &model);
      for (const std::string& w : semantic.warnings) err << "warning: " << w << "\n";
      for (const std::string& name : apply_srdf(semantic, model, acm)) {
        err << "warning: SRDF names '" << name << "', which is not a link of the robot\n";
      }
    }
    CheckerOptions options;
    options.padding = o.padding;
    if (o.sample_acm > 0) acm = with_sampled_pairs(o, srdf_xml, model, std::move(acm), options, err);
    const CollisionChecker checker(std::move(model), std::move(acm), options);
    if (o.print_acm) print_acm(checker, out);
    if (o.states.empty()) return 0;
    const RobotModel& m = checker.model();
    const States states = read_states(o.states, m);
    std::vector<double> state(m.variable_count(), 0.0);
    for (std::size_t v = 0; v < state.size(); ++v) {
      const RobotJoint& j = m.joints()[m.joint_index(m.variable_names()[v])];
      if (j.bounded) state[v] = std::clamp(0.0, j.lower, j.upper);
    }
    // The scene's objects (MoveIt .scene text or PlanningScene YAML), checked with the robot's own
    // pairs; a YAML scene's robot state gives the joints the states file leaves out, and places
    // the objects posed in a link's frame and those the robot holds.
    std::optional<Environment> world;
    if (!o.scene.empty()) {
      SceneFile scene = read_scene_file(o.scene);
      for (const std::string& w : scene.warnings) err << "warning: " << w << "\n";
      apply_scene_state(scene, m, state, err);
      place_in_world(scene, robot_scene_frames(m, srdf_xml, state.data()));  // (SRDF warnings shown once, above)
      world = scene.environment();
    }
    // A robot that holds objects checks them as links of its own (self and world).
    const CollisionChecker holding = world ? checker.carrying(*world, false) : checker;
    for (std::size_t i = 0; i < states.rows.size(); ++i) {
      for (std::size_t k = 0; k < states.variables.size(); ++k) state[states.variables[k]] = states.rows[i][k];
      print_state(o, holding, world ? &*world : nullptr, state, i, out);
    }
    return 0;
  } catch (const std::exception& e) {
    err << "bvh_collision_check: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace bvh_collision
