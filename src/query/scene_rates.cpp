// SceneChecker's rates: how fast each link and each checked self pair can move (close) over an
// interval of a straight motion, from the kinematic chain (query/scene_checker.h).
#include <algorithm>
#include <cmath>
#include <vector>

#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {

// Per checked pair, how fast the distance between its links can change per unit of each state
// variable: only the joints on the path between the two links change their relative pose (the
// deepest common ancestor's frame sees the joints above it move both alike, and a distance is the
// same in any frame), each at the rate of the link it moves (RobotCollisionModel::motion_rates:
// the farthest that link's geometry gets from the joint's axis). A pair with a prismatic joint
// on a chain (whose rate assumes its travel) or a joint that is no state variable keeps the sum
// of its links' own bounds.
void SceneChecker::relative_pair_rates() {
  const RobotModel& robot = checker_.model();
  const RobotCollisionModel& m = checker_.collision_model();
  std::vector<std::vector<int>> above(robot.links().size());  // joints from the root, per link
  for (const int j : robot.joint_order()) {
    const RobotJoint& joint = robot.joints()[j];
    above[joint.child_link] = above[joint.parent_link];
    if (joint.type != JointType::kFixed) above[joint.child_link].push_back(j);
  }
  auto variable_of = [&](int j) {
    const RobotJoint& joint = robot.joints()[j];
    return joint.mimic >= 0 ? robot.joints()[joint.mimic].variable : joint.variable;
  };
  for (const auto& [a, b] : m.checked_pairs()) {
    PairRates rates;
    rates.relative = m.motion_slides()[a].empty() && m.motion_slides()[b].empty();
    std::vector<double> w(robot.variable_count(), 0.0);
    for (const auto& [link, other] : {std::pair<int, int>{a, b}, std::pair<int, int>{b, a}}) {
      std::vector<char> moves(robot.variable_count(), 0);  // a joint of this side only has the variable
      for (const int j : above[link]) {
        if (std::find(above[other].begin(), above[other].end(), j) != above[other].end()) continue;  // moves both alike
        const int v = variable_of(j);
        if (v < 0) {
          rates.relative = rates.path_of_variables = false;
          continue;
        }
        moves[v] = 1;
      }
      // The link's rate for a variable covers every joint of its chain that the variable drives.
      for (std::size_t v = 0; v < w.size(); ++v) w[v] += moves[v] ? m.motion_rates()[link][v] : 0.0;
    }
    for (std::size_t v = 0; v < w.size(); ++v) {
      if (w[v] > 0.0) rates.weights.emplace_back(static_cast<int>(v), w[v]);
    }
    pair_rates_.push_back(std::move(rates));
  }
}

// Per link with geometry, its moving joints from the link up (a joint's child link carries its
// axis); per checked pair, how many of each side's joints lie below the part of the chain the
// two share (those above move both links alike).
void SceneChecker::interval_chains() {
  const RobotModel& robot = checker_.model();
  const std::size_t links = robot.links().size();
  chain_first_.assign(links, 0);
  chain_count_.assign(links, 0);
  for (const int l : links_) {
    chain_first_[l] = chain_joints_.size();
    for (int j = robot.links()[l].parent_joint; j >= 0; j = robot.links()[robot.joints()[j].parent_link].parent_joint) {
      const RobotJoint& joint = robot.joints()[j];
      const bool turns = joint.type == JointType::kRevolute || joint.type == JointType::kContinuous;
      if (!turns && joint.type != JointType::kPrismatic) continue;  // fixed, or posed from outside the state
      ChainJoint c;
      c.child = joint.child_link;
      c.variable = joint.mimic >= 0 ? robot.joints()[joint.mimic].variable : joint.variable;
      c.multiplier = joint.mimic >= 0 ? joint.multiplier : 1.0;
      if (c.variable < 0) continue;
      if (turns) {
        const auto known = std::find_if(turning_joints_.begin(), turning_joints_.end(), [&](const auto& t) { return t.first == c.child; });
        c.turning = static_cast<int>(known - turning_joints_.begin());
        if (known == turning_joints_.end()) {
          turning_joints_.emplace_back(c.child, joint.axis);
          turning_sources_.emplace_back(c.variable, c.multiplier);
        }
      }
      chain_joints_.push_back(c);
    }
    chain_count_[l] = chain_joints_.size() - chain_first_[l];
  }
  for (const auto& [a, b] : checker_.collision_model().checked_pairs()) {
    auto below = [&](int link, int other) {
      const auto first = chain_joints_.begin() + static_cast<std::ptrdiff_t>(chain_first_[link]);
      const auto other_first = chain_joints_.begin() + static_cast<std::ptrdiff_t>(chain_first_[other]);
      const auto other_end = other_first + static_cast<std::ptrdiff_t>(chain_count_[other]);
      int n = 0;
      for (auto it = first; it != first + static_cast<std::ptrdiff_t>(chain_count_[link]); ++it, ++n) {
        if (std::any_of(other_first, other_end, [&](const ChainJoint& o) { return o.child == it->child; })) break;
      }
      return n;
    };
    pair_below_.push_back({below(a, b), below(b, a)});
  }
}

// A point p of the link moves at v_p = sum_j d_j w_j x (p - o_j) (a slide: d_j u_j), d_j the
// joint's rate (its variable's change over the motion), w_j its axis through o_j. Two bounds on
// |v_p| over the interval, the smaller taken, joint by joint from the link up (each prefix bounds
// the speed the joints so far give the link in the frame above them, which a self pair needs):
// - levers: |d_j| times p's distance from axis j, which is at most its value at the midpoint plus
//   `half` times the speed the joints below j give p (turning about j keeps it);
// - velocity: at the midpoint |v_c| + |W| r for the link's ball (centre c, radius r; W = sum
//   d_j w_j), plus how much each term can change within the interval: its frame turns by at most
//   half * sum of |d_k| above j, and p moves in j's frame by at most half times the speed the
//   joints from j down give it.
//
// Written out on doubles, each quantity in the order Eigen evaluates it (the same bits), with the
// joints' changes and each link's turning total computed once a motion (chain_deltas) and each
// turning joint's origin and axis once an interval: a good part of the planner's motions is spent
// here (docs/performance.md).
double SceneChecker::chain_speed(int l, const Posed& mid, double half, const IntervalRates& rates, std::size_t joints) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const double cx = mid.centres[l][0], cy = mid.centres[l][1], cz = mid.centres[l][2];
  const double reach = m.bounds()[l].radius + m.paddings()[l] + pose_margin(mid.centre_norms[l]);
  const std::size_t first = chain_first_[l], end = first + joints;
  double turning_above = rates.turning_total[l];  // sum of |d_k| over the turning joints above the current one
  double* sums = rates.sums->data();
  const TurningAxis* axes = rates.axes->data();
  double below = 0.0, slides = 0.0, change = 0.0;
  double vx = 0.0, vy = 0.0, vz = 0.0, sx = 0.0, sy = 0.0, sz = 0.0;  // velocity and spin
  for (std::size_t i = first; i < end; ++i) {
    const ChainJoint& j = chain_joints_[i];
    const double d = rates.chain_delta[i], rate = std::abs(d);
    if (rate > 0.0 && j.turning < 0) {
      slides += rate;
      below += rate;
      change += rate * half * turning_above;  // the slide's direction turns with the frames above
    } else if (rate > 0.0) {
      turning_above -= rate;
      const TurningAxis& a = axes[j.turning];
      const double px = cx - a.origin[0], py = cy - a.origin[1], pz = cz - a.origin[2];
      const double along = (px * a.w[0] + py * a.w[1]) + pz * a.w[2];
      const double lever = std::sqrt(std::max(0.0, ((px * px + py * py) + pz * pz) - along * along)) + reach + a.origin_margin;
      const double farthest = lever + half * below;  // p's distance from the axis within the interval
      const double levers = below + rate * farthest;
      vx += d * (a.w[1] * pz - a.w[2] * py);
      vy += d * (a.w[2] * px - a.w[0] * pz);
      vz += d * (a.w[0] * py - a.w[1] * px);
      sx += d * a.w[0], sy += d * a.w[1], sz += d * a.w[2];
      change += rate * half * (std::max(turning_above, 0.0) * farthest + levers);
      const double velocity = std::sqrt((vx * vx + vy * vy) + vz * vz), spin = std::sqrt((sx * sx + sy * sy) + sz * sz);
      below = std::min(levers, velocity + spin * reach + slides + change);
    }
    sums[i] = below;
  }
  return std::min(rates.link_cap[l], below);
}

// Per chain joint its change over the motion, per link the sum of its turning joints', and the
// turning joints that turn (for chain_speed: the same over every interval of a motion; an axis it
// never reads is not posed: pr2's arm moves a third of its turning joints).
void SceneChecker::chain_deltas(const double* delta, std::vector<double>& chain_delta, std::vector<double>& turning_total,
                                std::vector<int>& turning_moving) const {
  chain_delta.resize(chain_joints_.size());
  for (std::size_t i = 0; i < chain_joints_.size(); ++i) chain_delta[i] = chain_joints_[i].multiplier * delta[chain_joints_[i].variable];
  // (The chain joints of a turning joint have its variable and multiplier: the same product.)
  turning_moving.clear();
  for (std::size_t t = 0; t < turning_sources_.size(); ++t) {
    if (turning_sources_[t].second * delta[turning_sources_[t].first] != 0.0) turning_moving.push_back(static_cast<int>(t));
  }
  turning_total.assign(chain_first_.size(), 0.0);
  for (const int l : links_) {
    double total = 0.0;
    for (std::size_t i = chain_first_[l]; i < chain_first_[l] + chain_count_[l]; ++i) {
      if (chain_joints_[i].turning >= 0) total += std::abs(chain_delta[i]);
    }
    turning_total[l] = total;
  }
}

void SceneChecker::interval_speeds(const Posed& mid, double half, const int* components, std::size_t count,
                                   const IntervalRates& rates) const {
  rates.sums->resize(chain_joints_.size());
  rates.axes->resize(turning_joints_.size());
  for (const int t : *rates.turning_moving) {
    const Transform& frame = mid.poses[turning_joints_[t].first];
    (*rates.axes)[t] = {frame.R * turning_joints_[t].second, frame.t, pose_margin(frame.t.norm())};
  }
  for (const int l : links_) rates.link_speed[l] = -1.0;
  // How many of each link's chain joints the components read: a link's speed all of them, a self
  // pair's the joints below its links' common ancestor only (panda's hand against its fifth link:
  // two of the hand's seven). Each link's chain is then walked once, as far as any reads it (the
  // walk's first entries are the same bits however far it goes).
  const auto& pairs = checker_.collision_model().checked_pairs();
  const int pair_count = static_cast<int>(pairs.size());
  std::vector<int>& reads = *rates.reads;
  std::vector<int>& read_links = *rates.read_links;
  reads.resize(chain_first_.size(), 0);
  read_links.clear();
  auto read = [&](int l, int joints) {
    if (joints <= 0) return;
    if (reads[l] == 0) read_links.push_back(l);
    reads[l] = std::max(reads[l], joints);
  };
  for (std::size_t i = 0; i < count; ++i) {
    const int k = components[i];
    if (k >= pair_count) {
      read(k - pair_count, std::max(1, static_cast<int>(chain_count_[k - pair_count])));
    } else {
      read(pairs[k].first, pair_below_[k][0]);
      read(pairs[k].second, pair_below_[k][1]);
    }
  }
  for (const int l : read_links) {
    const double speed = chain_speed(l, mid, half, rates, std::min<std::size_t>(reads[l], chain_count_[l]));
    if (reads[l] >= static_cast<int>(chain_count_[l])) rates.link_speed[l] = speed;
    reads[l] = 0;
  }
  const std::vector<double>& sums = *rates.sums;
  for (std::size_t i = 0; i < count; ++i) {
    const int k = components[i];
    if (k >= pair_count) continue;
    const auto [a, b] = pairs[k];
    const auto [na, nb] = pair_below_[k];
    const double relative = (na > 0 ? sums[chain_first_[a] + na - 1] : 0.0) + (nb > 0 ? sums[chain_first_[b] + nb - 1] : 0.0);
    rates.pair_speed[k] = std::min(rates.pair_cap[k], relative);
  }
}

}  // namespace bvh_collision
