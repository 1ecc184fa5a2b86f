// The Python module bvh_collision._core (imported as bvh_collision; docs/python.md): numpy arrays
// in and out of InProcessChecker (python/in_process_checker.h). The GIL is released around every
// call into the checker; float64 C-ordered arrays are read in place (others are converted once).
// Errors: std::invalid_argument becomes ValueError, every other error RuntimeError, with the C++
// message; a bad shape or dtype is a ValueError naming the argument.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "bvh_collision/python/in_process_checker.h"

namespace py = pybind11;

namespace bvh_collision {
namespace {

using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// Rows of `columns` values: (N, columns), or (columns,) as one row. Returns N.
std::size_t rows_of(const Doubles& a, std::size_t columns, const char* name) {
  const bool one = a.ndim() == 1 && static_cast<std::size_t>(a.shape(0)) == columns;
  const bool many = a.ndim() == 2 && static_cast<std::size_t>(a.shape(1)) == columns;
  if (!one && !many) {
    throw std::invalid_argument(std::string(name) + " must have shape (N, " + std::to_string(columns) + ") or (" +
                                std::to_string(columns) + ",), got " + shape_text(a));
  }
  return one ? 1 : static_cast<std::size_t>(a.shape(0));
}

std::vector<double> one_state(const InProcessChecker& c, const Doubles& q, const char* name) {
  if (q.ndim() != 1 || static_cast<std::size_t>(q.shape(0)) != c.dof()) {
    throw std::invalid_argument(std::string(name) + " must have shape (" + std::to_string(c.dof()) + ",), got " + shape_text(q));
  }
  return std::vector<double>(q.data(), q.data() + c.dof());
}

Vec3 vec3(const Doubles& a, const char* name) {
  if (a.ndim() != 1 || a.shape(0) != 3) throw std::invalid_argument(std::string(name) + " must have shape (3,), got " + shape_text(a));
  return Vec3(a.data()[0], a.data()[1], a.data()[2]);
}

// None: identity; a (4, 4) homogeneous matrix; or (7,): x, y, z, qx, qy, qz, qw.
Transform pose_of(const py::object& pose) {
  if (pose.is_none()) return Transform::Identity();
  const Doubles a = Doubles::ensure(pose);
  if (!a) throw std::invalid_argument("pose must be None, a (4, 4) matrix or (x, y, z, qx, qy, qz, qw)");
  Transform t;
  if (a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) t.R(r, c) = a.at(r, c);
      t.t[r] = a.at(r, 3);
    }
  } else if (a.ndim() == 1 && a.shape(0) == 7) {
    const double* p = a.data();
    const Eigen::Quaterniond q(p[6], p[3], p[4], p[5]);
    if (!(std::abs(q.norm() - 1.0) < 1e-6)) throw std::invalid_argument("pose: the quaternion is not of unit length");
    t.R = q.toRotationMatrix();
    t.t = Vec3(p[0], p[1], p[2]);
  } else {
    throw std::invalid_argument("pose must be None, a (4, 4) matrix or (x, y, z, qx, qy, qz, qw), got shape " + shape_text(a));
  }
  return t;
}

py::array_t<bool> bools(const std::vector<char>& v) {
  py::array_t<bool> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

py::array_t<double> doubles(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

StatesQuery query_of(bool self, bool environment, double tolerance, bool distance = false) {
  StatesQuery q;
  q.self = self, q.environment = environment, q.tolerance = tolerance, q.distance = distance;
  return q;
}

py::object check_states(const InProcessChecker& c, const Doubles& q, bool distance, bool self, bool environment, double tolerance) {
  const std::size_t n = rows_of(q, c.dof(), "q");
  StatesAnswer a;
  {
    py::gil_scoped_release unlocked;
    a = c.check_states(q.data(), n, query_of(self, environment, tolerance, distance));
  }
  if (!distance) return bools(a.valid);
  py::list pairs;
  for (std::size_t i = 0; i < n; ++i) pairs.append(py::make_tuple(a.nearest_a[i], a.nearest_b[i]));
  return py::make_tuple(bools(a.valid), doubles(a.distance), pairs);
}

py::tuple check_motions(const InProcessChecker& c, const Doubles& starts, const Doubles& goals, bool self, bool environment,
                        double tolerance) {
  const std::size_t n = rows_of(starts, c.dof(), "starts");
  if (rows_of(goals, c.dof(), "goals") != n) {
    throw std::invalid_argument("starts and goals must have the same shape, got " + shape_text(starts) + " and " + shape_text(goals));
  }
  MotionsAnswer a;
  {
    py::gil_scoped_release unlocked;
    a = c.check_motions(starts.data(), goals.data(), n, query_of(self, environment, tolerance));
  }
  return py::make_tuple(bools(a.valid), doubles(a.last_valid_fraction));
}

py::list contacts(const InProcessChecker& c, const Doubles& q, bool self, bool environment) {
  const std::vector<double> state = one_state(c, q, "q");
  std::vector<StateContact> found;
  {
    py::gil_scoped_release unlocked;
    found = c.contacts(state.data(), self, environment);
  }
  py::list out;
  for (const StateContact& k : found) {
    out.append(py::dict(py::arg("a") = k.a, py::arg("b") = k.b, py::arg("self") = k.self,
                        py::arg("position") = doubles({k.position.x(), k.position.y(), k.position.z()})));
  }
  return out;
}

py::dict cast_ray(const InProcessChecker& c, const Doubles& q, const Doubles& origin, const Doubles& direction, double max_range) {
  const std::vector<double> state = one_state(c, q, "q");
  const Vec3 o = vec3(origin, "origin"), d = vec3(direction, "direction");
  RayCastResult r;
  {
    py::gil_scoped_release unlocked;
    r = c.cast_ray(state.data(), o, d, max_range);
  }
  return py::dict(py::arg("hit") = r.hit, py::arg("distance") = r.distance,
                  py::arg("point") = doubles({r.point.x(), r.point.y(), r.point.z()}),
                  py::arg("link") = r.link >= 0 ? py::object(py::str(c.model().links()[r.link].name)) : py::object(py::none()),
                  py::arg("object") = r.object.empty() ? py::object(py::none()) : py::object(py::str(r.object)),
                  py::arg("octree") = r.octree);
}

py::dict insert_cloud(InProcessChecker& c, const py::array_t<float, py::array::c_style | py::array::forcecast>& points,
                      const Doubles& origin, const py::object& q, double max_range, double padding) {
  if (points.ndim() != 2 || points.shape(1) != 3) {
    throw std::invalid_argument("points must have shape (N, 3), got " + shape_text(points));
  }
  std::vector<ScanPoint> cloud(static_cast<std::size_t>(points.shape(0)));
  std::copy_n(points.data(), cloud.size() * 3, cloud.empty() ? nullptr : cloud.front().data());
  const ScanPoint sensor = vec3(origin, "origin").cast<float>();
  std::vector<double> state;
  if (!q.is_none()) state = one_state(c, Doubles::ensure(q), "q");
  ScanStats s;
  {
    py::gil_scoped_release unlocked;
    s = c.insert_cloud(cloud, sensor, state.empty() ? nullptr : state.data(), max_range, padding);
  }
  return py::dict(py::arg("points") = s.points, py::arg("skipped_invalid") = s.skipped_invalid,
                  py::arg("occupied") = s.occupied, py::arg("free") = s.free, py::arg("flipped") = s.flipped.size());
}

void add_mesh(InProcessChecker& c, const std::string& id, const Doubles& vertices, const Ints& triangles, const py::object& pose) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3) throw std::invalid_argument("vertices must have shape (V, 3), got " + shape_text(vertices));
  if (triangles.ndim() != 2 || triangles.shape(1) != 3) throw std::invalid_argument("triangles must have shape (T, 3), got " + shape_text(triangles));
  TriangleMesh mesh;
  const auto v = static_cast<std::size_t>(vertices.shape(0));
  for (std::size_t i = 0; i < v; ++i) mesh.vertices.emplace_back(vertices.at(i, 0), vertices.at(i, 1), vertices.at(i, 2));
  for (py::ssize_t i = 0; i < triangles.shape(0); ++i) {
    std::array<std::int32_t, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const std::int64_t index = triangles.at(i, k);
      if (index < 0 || static_cast<std::size_t>(index) >= v) {
        throw std::invalid_argument("triangle " + std::to_string(i) + " names vertex " + std::to_string(index) + " of " + std::to_string(v));
      }
      t[k] = static_cast<std::int32_t>(index);
    }
    mesh.triangles.push_back(t);
  }
  const Transform at = pose_of(pose);
  py::gil_scoped_release unlocked;
  c.add_object(id, ObjectShape::triangles(std::move(mesh)), at);
}

void add_shape(InProcessChecker& c, const std::string& id, const ObjectShape& shape, const py::object& pose) {
  const Transform at = pose_of(pose);
  py::gil_scoped_release unlocked;
  c.add_object(id, shape, at);
}

}  // namespace

// For the benchmark's C++ column (make bench, table `python`): check_states or check_motions on
// consecutive chunks of `batch` rows of a and b, each chunk timed inside C++ with no Python between;
// the seconds of each chunk. (Fresh rows each call: a motion asked again is answered from memory.)
void bind_timing(py::module_& m) {
  m.def("_cpp_seconds", [](const InProcessChecker& c, const std::string& kind, const Doubles& a, const Doubles& b, std::size_t batch) {
    const std::size_t n = rows_of(a, c.dof(), "a");
    if (rows_of(b, c.dof(), "b") != n) throw std::invalid_argument("a and b must have the same shape");
    if (kind != "states" && kind != "motions") throw std::invalid_argument("kind must be 'states' or 'motions'");
    if (batch == 0 || n % batch != 0) throw std::invalid_argument("the rows must be whole chunks of batch");
    std::vector<double> seconds;
    py::gil_scoped_release unlocked;
    for (std::size_t first = 0; first < n; first += batch) {
      const double* from = a.data() + first * c.dof();
      const double* to = b.data() + first * c.dof();
      const auto t0 = std::chrono::steady_clock::now();
      if (kind == "states") {
        c.check_states(from, batch, StatesQuery{});
      } else {
        c.check_motions(from, to, batch, StatesQuery{});
      }
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return seconds;
  }, py::arg("checker"), py::arg("kind"), py::arg("a"), py::arg("b"), py::arg("batch"));
}

}  // namespace bvh_collision

PYBIND11_MODULE(_core, m) {
  using namespace bvh_collision;
  m.doc() = "bvh_collision in-process: a robot's collision checker on numpy arrays (docs/python.md)";
  py::class_<InProcessChecker>(m, "Checker", "One robot and its world: states, motions, contacts, rays, clouds, objects")
      .def(py::init([](const std::string& urdf, const std::string& srdf, std::vector<std::string> package_paths, double padding,
                       std::vector<double> proxy_levels, std::string proxy_cache, double octree_resolution) {
             InProcessOptions o;
             o.package_paths = std::move(package_paths), o.padding = padding, o.proxy_levels = std::move(proxy_levels);
             o.proxy_cache = std::move(proxy_cache), o.octree_resolution = octree_resolution;
             py::gil_scoped_release unlocked;
             return std::make_unique<InProcessChecker>(urdf, srdf, o);
           }),
           py::arg("urdf"), py::arg("srdf") = "", py::arg("package_paths") = std::vector<std::string>{}, py::arg("padding") = 0.0,
           py::arg("proxy_levels") = std::vector<double>{}, py::arg("proxy_cache") = "", py::arg("octree_resolution") = 0.02)
      .def_property_readonly("joint_names", [](const InProcessChecker& c) { return c.model().variable_names(); })
      .def_property_readonly("dof", &InProcessChecker::dof)
      .def_property_readonly("limits", [](const InProcessChecker& c) {
        // (dof, 2): each variable's [lower, upper]; an unbounded joint [-pi, pi], as
        // random_configuration draws it.
        py::array_t<double> out({static_cast<py::ssize_t>(c.dof()), py::ssize_t(2)});
        for (std::size_t v = 0; v < c.dof(); ++v) out.mutable_at(v, 0) = -M_PI, out.mutable_at(v, 1) = M_PI;
        for (const RobotJoint& j : c.model().joints()) {
          if (j.variable < 0) continue;
          out.mutable_at(j.variable, 0) = j.bounded ? j.lower : -M_PI;
          out.mutable_at(j.variable, 1) = j.bounded ? j.upper : M_PI;
        }
        return out;
      }, "(dof, 2) array: each joint's lower and upper limit (an unbounded joint: -pi, pi)")
      .def_property_readonly("link_names", [](const InProcessChecker& c) {
        std::vector<std::string> names;
        for (const auto& l : c.model().links()) names.push_back(l.name);
        return names;
      })
      .def("check_states", &check_states, py::arg("q"), py::arg("distance") = false, py::arg("self") = true,
           py::arg("environment") = true, py::arg("tolerance") = 0.0)
      .def("check_motions", &check_motions, py::arg("starts"), py::arg("goals"), py::arg("self") = true,
           py::arg("environment") = true, py::arg("tolerance") = 0.0)
      .def("contacts", &contacts, py::arg("q"), py::arg("self") = true, py::arg("environment") = true)
      .def("cast_ray", &cast_ray, py::arg("q"), py::arg("origin"), py::arg("direction"), py::arg("max_range") = -1.0)
      .def("add_box", [](InProcessChecker& c, const std::string& id, const Doubles& size, const py::object& pose) {
             add_shape(c, id, ObjectShape::box(vec3(size, "size")), pose);
           }, py::arg("id"), py::arg("size"), py::arg("pose") = py::none())
      .def("add_sphere", [](InProcessChecker& c, const std::string& id, double r, const py::object& pose) {
             add_shape(c, id, ObjectShape::sphere(r), pose);
           }, py::arg("id"), py::arg("radius"), py::arg("pose") = py::none())
      .def("add_cylinder", [](InProcessChecker& c, const std::string& id, double r, double l, const py::object& pose) {
             add_shape(c, id, ObjectShape::cylinder(r, l), pose);
           }, py::arg("id"), py::arg("radius"), py::arg("length"), py::arg("pose") = py::none())
      .def("add_capsule", [](InProcessChecker& c, const std::string& id, double r, double l, const py::object& pose) {
             add_shape(c, id, ObjectShape::capsule(r, l), pose);
           }, py::arg("id"), py::arg("radius"), py::arg("length"), py::arg("pose") = py::none())
      .def("add_cone", [](InProcessChecker& c, const std::string& id, double r, double l, const py::object& pose) {
             add_shape(c, id, ObjectShape::cone(r, l), pose);
           }, py::arg("id"), py::arg("radius"), py::arg("length"), py::arg("pose") = py::none())
      .def("add_mesh", &add_mesh, py::arg("id"), py::arg("vertices"), py::arg("triangles"), py::arg("pose") = py::none())
      .def("remove_object", &InProcessChecker::remove_object, py::arg("id"), py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("object_ids", &InProcessChecker::object_ids)
      .def("load_scene", [](InProcessChecker& c, const std::string& path, const py::object& q) {
             const std::vector<double> state = q.is_none() ? std::vector<double>(c.dof(), 0.0) : one_state(c, Doubles::ensure(q), "q");
             py::gil_scoped_release unlocked;
             return c.load_scene(path, state.data());
           }, py::arg("path"), py::arg("q") = py::none())
      .def("attach", [](InProcessChecker& c, const std::string& id, const std::string& link, const Doubles& q,
                        const std::vector<std::string>& touch_links) {
             const std::vector<double> state = one_state(c, q, "q");
             py::gil_scoped_release unlocked;
             c.attach(id, link, state.data(), touch_links);
           }, py::arg("id"), py::arg("link"), py::arg("q"), py::arg("touch_links") = std::vector<std::string>{})
      .def("detach", [](InProcessChecker& c, const std::string& id, const Doubles& q) {
             const std::vector<double> state = one_state(c, q, "q");
             py::gil_scoped_release unlocked;
             return c.detach(id, state.data());
           }, py::arg("id"), py::arg("q"))
      .def_property_readonly("attached_ids", &InProcessChecker::attached_ids)
      .def("insert_cloud", &insert_cloud, py::arg("points"), py::arg("origin"), py::arg("q") = py::none(),
           py::arg("max_range") = -1.0, py::arg("self_filter_padding") = 0.02)
      .def("load_octree", &InProcessChecker::load_octree, py::arg("path"), py::call_guard<py::gil_scoped_release>())
      .def("save_octree", &InProcessChecker::save_octree, py::arg("path"), py::call_guard<py::gil_scoped_release>())
      .def("clear_octree", &InProcessChecker::clear_octree, py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("occupied_voxels", &InProcessChecker::occupied_voxels)
      .def_property_readonly("octree_resolution", &InProcessChecker::octree_resolution)
      .def("add_proxy_level", &InProcessChecker::add_proxy_level, py::arg("level"), py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("proxy_levels", &InProcessChecker::proxy_levels);
  bind_timing(m);
}
