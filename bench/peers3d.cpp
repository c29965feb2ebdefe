// OMPL in C++ as the peer of `skyplan bench --3d --peers`: RRTConnect, PRM and RRT* in R^3 over
// the same grown boxes as skyplan, with validity and motion checks as exact as skyplan's.
//
// Built by the bench (g++ -O2, pkg-config ompl: Debian's libompl-dev), run as
//   peers3d PROBLEM.txt BUDGET_S
// PROBLEM.txt: "nboxes nqueries", the bounds (6 numbers: minN minE minAlt maxN maxE maxAlt), then
// nboxes lines of 6 numbers (boxes already grown by the margin, closed: touching one is a
// collision) and nqueries lines of 6 (start N E Alt, goal N E Alt).
//
// Validity: a state is valid iff it is inside the bounds and in no box (a uniform grid of 25 m
// north/east buckets finds the candidate boxes). Motion: an exact continuous segment-box test
// (slab method) against every box whose bucket the segment's bounding rectangle touches, in place
// of OMPL's default discrete checking at a resolution: no resolution to choose, no motion that
// grazes a box between two checks. Every simplified path is re-checked segment by segment with
// the same exact test (recheck_ok), as skyplan's are.
//
// Prints one JSON line per (peer, query): {"peer", "query", "time_s" (to the first exact
// solution; RRT*: the whole budget), "solved", "length_m", "recheck_ok", "path" (the simplified
// path's points, for an independent re-check)}.
#include <ompl/base/MotionValidator.h>
#include <ompl/base/objectives/PathLengthOptimizationObjective.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/prm/PRM.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace ob = ompl::base;
namespace og = ompl::geometric;

using Vec3 = std::array<double, 3>;

struct Box {
  Vec3 lo, hi;
};

// The boxes and a uniform north/east bucket grid over them.
struct World {
  Vec3 bmin{}, bmax{};
  std::vector<Box> boxes;
  double cell = 25.0;
  int rows = 1, cols = 1;
  std::vector<std::vector<int>> buckets;

  int row(double n) const { return std::clamp(int(std::floor((n - bmin[0]) / cell)), 0, rows - 1); }
  int col(double e) const { return std::clamp(int(std::floor((e - bmin[1]) / cell)), 0, cols - 1); }

  void index() {
    rows = std::max(1, int(std::ceil((bmax[0] - bmin[0]) / cell)));
    cols = std::max(1, int(std::ceil((bmax[1] - bmin[1]) / cell)));
    buckets.assign(size_t(rows) * cols, {});
    for (int i = 0; i < int(boxes.size()); ++i) {
      const Box &b = boxes[i];
      for (int r = row(b.lo[0]); r <= row(b.hi[0]); ++r)
        for (int c = col(b.lo[1]); c <= col(b.hi[1]); ++c) buckets[size_t(r) * cols + c].push_back(i);
    }
  }

  bool in_bounds(const Vec3 &p) const {
    for (int k = 0; k < 3; ++k)
      if (p[k] < bmin[k] || p[k] > bmax[k]) return false;
    return true;
  }

  static bool in_box(const Vec3 &p, const Box &b) {
    for (int k = 0; k < 3; ++k)
      if (p[k] < b.lo[k] || p[k] > b.hi[k]) return false;
    return true;
  }

  bool point_free(const Vec3 &p) const {
    if (!in_bounds(p)) return false;
    for (int i : buckets[size_t(row(p[0])) * cols + col(p[1])])
      if (in_box(p, boxes[i])) return false;
    return true;
  }

  // Does the closed segment a-b meet the closed box? (slab method)
  static bool segment_hits(const Vec3 &a, const Vec3 &b, const Box &x) {
    double enter = 0.0, leave = 1.0;
    for (int k = 0; k < 3; ++k) {
      double d = b[k] - a[k];
      if (d == 0.0) {
        if (a[k] < x.lo[k] || a[k] > x.hi[k]) return false;
      } else {
        double t1 = (x.lo[k] - a[k]) / d, t2 = (x.hi[k] - a[k]) / d;
        enter = std::max(enter, std::min(t1, t2));
        leave = std::min(leave, std::max(t1, t2));
        if (enter > leave) return false;
      }
    }
    return true;
  }

  bool segment_free(const Vec3 &a, const Vec3 &b, std::vector<int> &seen, int stamp) const {
    if (!in_bounds(a) || !in_bounds(b)) return false;
    int r0 = row(std::min(a[0], b[0])), r1 = row(std::max(a[0], b[0]));
    int c0 = col(std::min(a[1], b[1])), c1 = col(std::max(a[1], b[1]));
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c)
        for (int i : buckets[size_t(r) * cols + c]) {
          if (seen[i] == stamp) continue;
          seen[i] = stamp;
          if (segment_hits(a, b, boxes[i])) return false;
        }
    return true;
  }
};

static Vec3 vec(const ob::State *s) {
  const auto *v = s->as<ob::RealVectorStateSpace::StateType>();
  return {v->values[0], v->values[1], v->values[2]};
}

// OMPL's motion check, exact: the whole straight motion against the boxes.
class ExactMotion : public ob::MotionValidator {
 public:
  ExactMotion(const ob::SpaceInformationPtr &si, const World &w)
      : ob::MotionValidator(si), world_(w), seen_(w.boxes.size(), -1) {}
  bool checkMotion(const ob::State *s1, const ob::State *s2) const override {
    bool ok = world_.segment_free(vec(s1), vec(s2), seen_, ++stamp_);
    if (ok) ++valid_; else ++invalid_;
    return ok;
  }
  bool checkMotion(const ob::State *s1, const ob::State *s2,
                   std::pair<ob::State *, double> &last) const override {
    if (checkMotion(s1, s2)) return true;
    // The last valid point: bisect the free prefix to 1 mm (used by RRT-style extension).
    Vec3 a = vec(s1), b = vec(s2);
    double lo = 0.0, hi = 1.0, len = std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                                               (b[2] - a[2]) * (b[2] - a[2]));
    while ((hi - lo) * len > 1e-3) {
      double mid = 0.5 * (lo + hi);
      Vec3 m{a[0] + (b[0] - a[0]) * mid, a[1] + (b[1] - a[1]) * mid, a[2] + (b[2] - a[2]) * mid};
      if (world_.segment_free(a, m, seen_, ++stamp_)) lo = mid; else hi = mid;
    }
    if (last.first != nullptr) {
      auto *v = last.first->as<ob::RealVectorStateSpace::StateType>();
      for (int k = 0; k < 3; ++k) v->values[k] = a[k] + (b[k] - a[k]) * lo;
    }
    last.second = lo;
    return false;
  }

 private:
  const World &world_;
  mutable std::vector<int> seen_;
  mutable int stamp_ = 0;
};

static bool read_problem(const char *path, World &w, std::vector<std::array<double, 6>> &queries) {
  std::ifstream in(path);
  size_t nb = 0, nq = 0;
  if (!(in >> nb >> nq)) return false;
  for (int k = 0; k < 3; ++k) in >> w.bmin[k];
  for (int k = 0; k < 3; ++k) in >> w.bmax[k];
  w.boxes.resize(nb);
  for (auto &b : w.boxes) {
    for (int k = 0; k < 3; ++k) in >> b.lo[k];
    for (int k = 0; k < 3; ++k) in >> b.hi[k];
  }
  queries.resize(nq);
  for (auto &q : queries)
    for (double &v : q) in >> v;
  return bool(in);
}

int main(int argc, char **argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: peers3d PROBLEM.txt BUDGET_S\n");
    return 2;
  }
  World world;
  std::vector<std::array<double, 6>> queries;
  if (!read_problem(argv[1], world, queries)) {
    std::fprintf(stderr, "peers3d: cannot read the problem %s\n", argv[1]);
    return 2;
  }
  const double budget_s = std::atof(argv[2]);
  world.index();
  ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
  auto space = std::make_shared<ob::RealVectorStateSpace>(3);
  ob::RealVectorBounds rb(3);
  for (int k = 0; k < 3; ++k) {
    rb.setLow(k, world.bmin[k]);
    rb.setHigh(k, world.bmax[k]);
  }
  space->setBounds(rb);
  const char *names[] = {"ompl-cpp-rrtconnect", "ompl-cpp-prm", "ompl-cpp-rrtstar"};
  std::vector<int> seen(world.boxes.size(), -1);
  int stamp = 0;
  for (int p = 0; p < 3; ++p) {
    for (size_t k = 0; k < queries.size(); ++k) {
      const auto &q = queries[k];
      og::SimpleSetup ss(space);
      auto si = ss.getSpaceInformation();
      ss.setStateValidityChecker([&world](const ob::State *s) { return world.point_free(vec(s)); });
      si->setMotionValidator(std::make_shared<ExactMotion>(si, world));
      ob::ScopedState<> start(space), goal(space);
      for (int d = 0; d < 3; ++d) {
        start[d] = q[d];
        goal[d] = q[3 + d];
      }
      ss.setStartAndGoalStates(start, goal);
      // PRM stops at its first path (any length satisfies the objective); RRT* improves its path
      // for the whole budget (no length does), as skyplan's RRT* does.
      auto objective = std::make_shared<ob::PathLengthOptimizationObjective>(si);
      objective->setCostThreshold(ob::Cost(p == 2 ? 0.0 : std::numeric_limits<double>::infinity()));
      ss.setOptimizationObjective(objective);
      if (p == 0) ss.setPlanner(std::make_shared<og::RRTConnect>(si));
      if (p == 1) ss.setPlanner(std::make_shared<og::PRM>(si));
      if (p == 2) ss.setPlanner(std::make_shared<og::RRTstar>(si));
      ss.setup();
      auto t0 = std::chrono::steady_clock::now();
      ob::PlannerStatus solved = ss.solve(budget_s);
      double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      bool exact = bool(solved) && ss.haveExactSolutionPath();
      std::printf("{\"peer\": \"%s\", \"query\": %zu, \"time_s\": %.9f, \"solved\": %s", names[p], k, dt,
                  exact ? "true" : "false");
      if (exact) {
        ss.simplifySolution();
        const og::PathGeometric &path = ss.getSolutionPath();
        double length = 0.0;
        bool recheck = true;
        for (size_t i = 0; i + 1 < path.getStateCount(); ++i) {
          Vec3 a = vec(path.getState(i)), b = vec(path.getState(i + 1));
          length += std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
          recheck = recheck && world.point_free(a) && world.point_free(b) && world.segment_free(a, b, seen, ++stamp);
        }
        std::printf(", \"length_m\": %.6f, \"recheck_ok\": %s, \"path\": [", length, recheck ? "true" : "false");
        for (size_t i = 0; i < path.getStateCount(); ++i) {
          Vec3 a = vec(path.getState(i));
          std::printf("%s[%.17g, %.17g, %.17g]", i ? ", " : "", a[0], a[1], a[2]);
        }
        std::printf("]");
      }
      std::printf("}\n");
      std::fflush(stdout);
    }
  }
  return 0;
}
