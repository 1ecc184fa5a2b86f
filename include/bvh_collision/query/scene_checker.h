// CollisionChecker bound to one environment snapshot, prepared for a planner's many questions: a
// boolean check of one state and a certified check of one motion, with nothing per call but the
// geometry (no batch, no pool, no allocation once warm). Same answers and the same contract as
// check_self + check_environment and check_motion (docs/design.md sections 2 and 4):
//
// - State: exact by default (with SceneCheckOptions::states_at_tolerance, collision whenever
//   some distance is at most its padding, free whenever every one exceeds padding + tolerance).
//   Objects are found through a grid over the robot's reach (a link's centre names a cell, the
//   cell lists the objects within reach of it, each with a lower bound on its distance from the
//   cell: a link ball smaller needs no test), so 60 objects cost little more than 6; each
//   link's proxy spheres are tested against an object's exact primitive before any mesh is
//   opened: proxies apart from it prove the link apart (they contain it), and a proxy that meets
//   it sends the link to the exact test (or, at a tolerance the level fits, is the answer).
//   A (link, object) pair the environment allows to touch (Environment::allowed_collisions) is
//   not checked, in states and motions alike.
// - Motion: an interval [s0, s1] of the straight joint-space segment is certified free by one
//   boolean check of the proxies at its midpoint, each link's grown by how far any of its points
//   can move in half the interval (from the arm's pose at the midpoint: chain_speed, capped by
//   CollisionChecker::link_speed's chain-length levers) and each self pair's by how far its links
//   can close (the joints between the two links only); an interval that fails is bisected, breadth first, its midpoint
//   state checked (a collision there ends the motion). Once the growth is below the proxies' own
//   error, an exact distance at the midpoint settles a link or pair (farther than its growth:
//   free over the interval). At a tolerance t, an interval whose growth and proxy error fit in t
//   and still fails is within t of a collision (reported colliding, as the tolerance allows),
//   for the self pairs and links (components) that are clear of t at both ends of the motion; one
//   within t at an end is settled exactly (a planner must be able to leave the state it stands
//   in, and a base resting on the floor must not make every motion exact). Free means free at
//   every instant, farther than min_clearance from every collision, at any tolerance; a component
//   closer than twice min_clearance at an end (a valid state, 0.2 um from a contact) keeps the
//   largest min_clearance / 2^j whose double both ends clear instead, at least 10 nm (a quarter to
//   a half of the nearer end's clearance): a planner can reach and leave any state it accepted
//   beyond 20 nm of a contact (scene_ends.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/world/object_grid.h"

namespace bvh_collision {

struct SceneCheckOptions {
  bool self = true, environment = true;
  double tolerance = 0.0;  // docs/design.md
  Transform root_pose;     // the root link in the environment's frame
  // Motions: one answered free stays farther than this from every collision; one that comes
  // within it may count as colliding (as MotionRequest::min_clearance; this one within twice
  // times it), and beyond max_intervals interval checks a motion is not certified.
  double min_clearance = 1e-5;
  std::size_t max_intervals = 200000;
  // False (the default): state checks are exact whatever the tolerance (the proxies prove a
  // state free, an exact test confirms a hit), so that a planner can accept a goal a millimetre
  // from a table; true: a state within the tolerance may count as colliding (cheaper hits).
  bool states_at_tolerance = false;
  // At tolerance 0, a self pair that an interval's proxies cannot certify takes its exact
  // distance at the midpoint once its growth is at most this (m; never below the finest level,
  // where halving the interval no longer helps the proxies); below it the interval is halved.
  // Negative: the checker's own (RobotAccelerators::pair_exact_growth, chosen when its levels
  // were built: query/motion_calibration.h). The answers are the same at every value.
  double pair_exact_growth = -1.0;
  // A self pair that a motion moves by one joint of its kinematic path, the path's other joints
  // held (a planning group beside a tucked arm), is proven clear along that joint once per thread
  // and robot model, and read back by every later motion (src/query/held_pair_clearance.h). False:
  // every interval settles it afresh (for tests and measurements: the answers are the same).
  bool held_pairs = true;
};

class SceneChecker {
 public:
  // Throws std::invalid_argument for a null environment, a bad root pose or tolerance. Builds the
  // object grid, and the octree's distance field when there is an octree and none is kept. The
  // objects the environment has attached are carried (CollisionChecker::carrying) unless
  // `checker` carries them already.
  SceneChecker(CollisionChecker checker, std::shared_ptr<const Environment> environment, const SceneCheckOptions& options = {});

  // Boolean: is `state` (model().variable_count() values) in collision at the tolerance? Throws
  // std::invalid_argument, naming the variable, for a value that is not finite (as check_motion).
  bool collides(const double* state) const;
  // The straight motion, certified as above (MotionResult::states_checked counts intervals; 0
  // when this thread asked this checker the same motion before and the answer is remembered).
  // `earliest`: find the first collision, so that last_valid_fraction is where a planner can go
  // (intervals depth first, left first, each collision found narrowing the search to before
  // it); otherwise intervals breadth first, stopping at any collision (a boolean answer).
  MotionResult check_motion(const double* start, const double* goal, bool earliest = false) const;

  const CollisionChecker& checker() const { return checker_; }
  const Environment& environment() const { return *env_; }
  const SceneCheckOptions& options() const { return options_; }
  // The proxy levels tests go through, coarsest first (a pair or link apart at one is apart; the
  // last decides or sends it to the exact test); empty when none is built: then only exact tests.
  const std::vector<const ProxyLevel*>& proxies() const { return proxies_; }

  // How far any point of link `l` can move over the interval [lo, hi] of the segment (fractions)
  // from where it is at the interval's midpoint, from the arm's pose there (chain_speed: the
  // joints' levers and the link's velocity at the midpoint, plus how much either can change
  // within the interval; never more than the chain-length bound). Exported for the test that
  // checks it against sampled motion; the motions use the same bound.
  double link_growth(int link, const double* start, const double* goal, double lo, double hi) const;
  // How far the distance between the links of checked pair `pair` can fall over such an
  // interval: only the joints on the path between the two links count (proven by a test the same way).
  double pair_growth(std::size_t pair, const double* start, const double* goal, double lo, double hi) const;

 private:
  // kFree: free for every state whose links lie within their growth of these poses; kHit: the
  // state itself collides (exact, or within the tolerance); kNear: an interval not certified.
  enum class Answer { kFree, kHit, kNear };
  // One state as the tests read it: the state, its link poses (root pose applied), the world
  // centres of the links' bounding spheres, and per link a growth (null: the state itself).
  struct Posed {
    const double* state = nullptr;
    std::vector<Transform> poses;
    std::vector<Vec3> centres;
    std::vector<double> centre_norms;  // |centre| per link, for the rounding margins
    double largest_norm = 0.0;         // of centre_norms (the links with geometry)
    const double* growth = nullptr;
    const double* pair_growth = nullptr;  // per checked pair: how far its links' distance can fall
    const double* from = nullptr;         // the interval's end states (with growth)
    const double* to = nullptr;
    // A hit within the tolerance may count (the state itself), or an interval is not to be
    // settled by exact distances (growth: the tolerance will settle it). Read only where the
    // proxies could not prove the component apart; on a motion's interval it is asked of the
    // motion's ends then, once per component (`ends` set: SceneChecker::tolerant_component).
    bool tolerant_flag = false;
    // The caller has already tested each pair's bounding balls with this growth (an interval's
    // sieve, a state's): pair_check does not test them again.
    mutable bool balls_sieved = false;
    // Per checked pair, the leaf spheres that last met on this posed scratch (proxies_overlap):
    // its next interval or state is mostly close to its last.
    mutable std::vector<ProxyWitness> witnesses;
    // Per link and object (link * objects + object), the leaf sphere of the link's that last met it.
    mutable std::vector<std::int32_t> object_witnesses;
    const SceneChecker* checker = nullptr;
    Posed* ends = nullptr;
    int component = -1;
    bool tolerant() const { return ends != nullptr ? checker->tolerant_component(component, ends) : tolerant_flag; }
    double grow(int link) const { return growth != nullptr ? growth[link] : 0.0; }
    // An interval's half-width, and the stretch around its midpoint (fractions) over which every
    // component that failed on an exact distance stays free: a gap `gap` beyond padding and a
    // growth `growth` over the half-width free half * gap / growth. One that failed otherwise
    // frees nothing (0).
    double half = 0.0;
    mutable double free_radius = 0.0;
    // The clearance the interval keeps for `component` (end_clearance_floor); a stretch is freed
    // only where the component stays farther than it (infinite: none is).
    double clearance = std::numeric_limits<double>::infinity();
    // Since the last clear_gaps: did every failure of a component come from an exact distance at
    // the midpoint beyond its padding (1), another failure (0), or none yet (-1)? All beyond: the
    // midpoint itself is free of that component.
    mutable signed char gaps = -1;
    void clear_gaps() const { gaps = -1; }
    void note_free_radius(double gap, double growth_now) const {
      free_radius = std::min(free_radius, gap > 0.0 && growth_now > 0.0 ? half * gap / growth_now : 0.0);
      gaps = gap > 0.0 && gaps != 0 ? 1 : 0;
    }
    Answer no_free_radius() const {
      free_radius = 0.0;
      gaps = 0;
      return Answer::kNear;
    }
  };

  // A thread's working memory for motions (scene_motion.cpp), kept between them: a planner's
  // millionth motion allocates nothing.
  struct MotionScratch;
  static MotionScratch& motion_scratch();

  Answer check_posed(const Posed& posed) const;
  Answer check_still(const Posed& posed) const;  // check_posed for a state (no growth)
  // One component: a checked self pair or one link against the environment (components_).
  Answer component_check(int k, const Posed& posed) const;
  bool exact_distance_pays(const Posed& s, double growth, double error) const;
  bool worth(const ProxyLevel* level, double growth) const;
  const ProxyLevel* walked_level(double growth) const;
  Answer pair_check(std::size_t pair, const Posed& posed) const;
  // pair_check's first test: are the pair's bounding balls apart by more than their paddings and
  // growth? (Most pairs of a two-arm robot end here in most intervals: the interval loop asks it
  // before the call.)
  bool pair_balls_apart(std::size_t pair, const Posed& posed) const;
  // Over a motion's interval that moves one variable of the pair's kinematic path and holds the
  // others (from, to: its end states): is the pair proven clear all along by the thread's held
  // tree for it (held_pair_clearance.h)?
  bool held_pair_clear(std::size_t pair, const double* from, const double* to) const;
  Answer link_objects_check(int link, const Posed& posed) const;
  Answer link_octree_check(int link, const Posed& posed) const;
  bool link_meets_object_exact(int link, const Transform& pose, int object, double tolerance) const;
  // The link's exact distance to the object when below `limit` (else `limit` or a little more).
  double link_object_distance(int link, const Transform& pose, int object, double limit) const;
  // One interval of a motion, for the components pending over it: certified, a collision at
  // `at`, or to be split; the components it could not certify for what follows (first, count).
  struct Step {
    enum Outcome { kCertified, kCollides, kSplit } outcome;
    double at = -1.0;
    std::size_t first = 0, count = 0;
    double free_lo = 0.0, free_hi = 0.0;  // kSplit: a middle stretch already free (when free_hi > free_lo)
    double largest = 0.0;                 // kSplit: the most a failing component moves over half the interval
  };
  template <class At>
  Step check_interval(double lo, double hi, std::size_t first, std::size_t count, At&& at,
                      Posed* ends) const;
  bool tolerant_component(int k, Posed* ends) const;
  // Is component k clear by more than `grow` at both ends? (`exact` false: proxies alone decide.)
  bool clear_at_ends(int k, Posed* ends, double grow, bool exact) const;
  double end_clearance_floor(int k, Posed* ends) const;
  bool closer_end_splits(const int* first, const int* last, double half, Posed* ends) const;
  bool failure_within_tolerance(int k, const Posed& mid) const;
  void pose_goal(Posed* ends) const;
  void pose_links(const double* state, Posed& posed) const;
  // A motion's intervals: `posed` holds the motion's start (pose_links), and only the links below
  // a joint the motion turns or slides are posed again (moving_links chose them). A two-arm
  // robot's arm motion poses its arms, not its body, head and sensors at every interval.
  void moving_links(const double* start, const double* goal, const Posed& at_start) const;
  // (Of those, only the links that the `count` pending components read and the links they hang
  // from, when some components are certified: the others keep poses no test of the interval reads.)
  void pose_moving_links(const double* state, Posed& posed, const int* components, std::size_t count) const;
  void needed_links(const int* components, std::size_t count) const;
  void relative_pair_rates();
  void interval_chains();
  void motion_speeds(const double* start, const double* goal) const;
  void chain_deltas(const double* delta, std::vector<double>& chain_delta, std::vector<double>& turning_total,
                    std::vector<int>& turning_moving) const;
  void speeds_over(const double* start, const double* goal, double lo, double hi) const;
  // A turning joint at an interval's midpoint: its axis, and the rounding margin of its origin
  // (the same for every link below it: computed once an interval, not once a link).
  struct TurningAxis {
    Vec3 w, origin;
    double origin_margin;
  };
  // An interval's rates: per link and per checked pair, how fast they can move (close) per unit
  // fraction over the interval of half-width `half` around `mid` (posed): the midpoint's levers,
  // capped by the motion's chain-length rates. Computed for the components asked only.
  struct IntervalRates {
    const double* delta = nullptr;  // goal - start
    const double* chain_delta = nullptr;    // per chain joint: its change over the motion (multiplier applied)
    const double* turning_total = nullptr;  // per link: the sum of |chain_delta| over its turning joints
    const double* link_cap = nullptr;
    const double* pair_cap = nullptr;
    double* link_speed = nullptr;  // out (per link; links not asked for are left negative)
    double* pair_speed = nullptr;  // out (per checked pair)
    std::vector<double>* sums = nullptr;  // working memory: per chain joint
    std::vector<TurningAxis>* axes = nullptr;  // working memory: per turning joint, at `mid`
    const std::vector<int>* turning_moving = nullptr;  // the turning joints the motion turns (chain_speed reads only theirs)
    std::vector<int>* reads = nullptr;  // working memory: per link, how many of its chain joints the components read
    std::vector<int>* read_links = nullptr;  // working memory: the links with reads set
  };
  void interval_speeds(const Posed& mid, double half, const int* components, std::size_t count, const IntervalRates& rates) const;
  // Over link l's first `joints` chain joints (from the link up; its speed when that is all of them).
  double chain_speed(int link, const Posed& mid, double half, const IntervalRates& rates, std::size_t joints) const;


  // A state this thread found free with this checker, asked again (a tree's node starts every
  // motion grown from it): known_free answers from memory, remember_free records one.
  bool known_free(const double* state) const;
  void remember_free(const double* state) const;
  struct StateScratch;
  static StateScratch& state_scratch();
  std::size_t state_slot(const double* state) const;  // its slot in the memory of free states
  bool known_free(const StateScratch& scratch, const double* state, std::size_t slot) const;  // slot: slot_of(state)
  void remember_free(StateScratch& scratch, const double* state, std::size_t slot) const;
  // A motion this thread answered with this checker, asked again (the same ends and kind, bit for
  // bit): known_motion gives the answer it had (states_checked 0), remember_motion records one.
  bool known_motion(const double* start, const double* goal, bool earliest, MotionResult& result) const;
  void remember_motion(const double* start, const double* goal, bool earliest, const MotionResult& result) const;
  MotionResult check_motion_once(const double* start, const double* goal, bool earliest) const;
  // A motion within one this thread certified free with this checker (both ends on its segment,
  // to within rounding): free. remember_free_motion records one.
  bool within_free_motion(const double* start, const double* goal) const;
  void remember_free_motion(const double* start, const double* goal) const;
  // How far (metres) a remembered free segment's certificate is trusted to stretch: the most any
  // link may move between a motion's states and the segment's (within_free_motion).
  static constexpr double kSegmentDisplacement = 1e-12;

  CollisionChecker checker_;
  std::shared_ptr<const Environment> env_;
  // Numbered at construction (copies share it: they answer alike), so that the memory of free
  // states never answers for another checker, even one built where a destroyed one stood.
  std::uint64_t serial_ = 0;
  SceneCheckOptions options_;
  std::vector<const ProxyLevel*> proxies_;  // coarsest first; the last is the finest used
  double level_ = 0.0;                       // the finest's
  double pair_exact_growth_ = 0.0;           // SceneCheckOptions::pair_exact_growth, at least level_
  bool proxies_decide_self_ = false;         // tolerance >= the finest level: overlap is an answer
  bool proxies_decide_objects_ = false;      // tolerance >= half of it
  // A motion may take the tolerance's shortcuts (a tolerance, with a level that fits it):
  // then each component that fails is asked whether it is clear of the tolerance at both ends.
  bool tolerance_asked_ = false;
  std::shared_ptr<const OctreeDistanceField> field_;
  ObjectGrid grid_;
  std::vector<char> allowed_;  // per link and object (link * objects + object): allowed to touch; empty: none is
  std::vector<int> links_;  // the links with geometry
  // What one check covers, in checking order: checked self pairs (their indices), then each
  // link's environment (the pair count plus the link).
  std::vector<int> components_;
  bool root_at_origin_ = true;  // the root pose is the identity: link poses need no product
  double largest_radius_ = 0.0;  // of the links' bounding radii
  std::vector<double> link_reach_;  // per link: its bounding radius and padding
  bool octree_ = false;          // the environment has one
  struct PairRates {
    bool relative = true;  // false: the sum of the two links' own bounds
    // Every joint on the pair's path is a state variable's: the weights' variables are all that
    // change the pair's relative pose, each closing it at most at its weight (prismatic joints
    // too: a link's motion rates bound its points' speed in any state within the limits).
    bool path_of_variables = true;
    std::vector<std::pair<int, double>> weights;  // (state variable, rate)
  };
  std::vector<PairRates> pair_rates_;  // per checked pair
  struct PairBalls {
    int a, b;
    double reach;  // the links' bounding radii and paddings, summed
  };
  std::vector<PairBalls> pair_balls_;  // per checked pair
  // Per link with geometry, the moving joints above it, the link's own first: a joint turns
  // (or slides) the link about the axis through its child link's origin.
  struct ChainJoint {
    int child = -1, variable = -1;
    double multiplier = 1.0;
    int turning = -1;  // its index in turning_joints_ (-1: a slide)
  };
  std::vector<ChainJoint> chain_joints_;
  std::vector<std::pair<int, Vec3>> turning_joints_;  // each turning joint once: (child link, unit axis in its frame)
  std::vector<std::pair<int, double>> turning_sources_;  // per turning joint: (state variable, multiplier)
  std::vector<std::size_t> chain_first_, chain_count_;  // per link: its run of chain_joints_ (and of sums)
  std::vector<std::array<int, 2>> pair_below_;           // per checked pair: each side's joints below the common part
};

}  // namespace bvh_collision
