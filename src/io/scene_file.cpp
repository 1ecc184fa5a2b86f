// MoveIt `.scene` text in and out (io/scene_file.h).
#include "bvh_collision/io/scene_file.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <unordered_map>

namespace bvh_collision {

namespace {

constexpr double kLargest = 1e5;  // metres: beyond it corners and products lose their digits (as the URDF rule)
constexpr std::uintmax_t kLargestFile = 64u << 20;

std::string trimmed(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

// The file as lines, read token by token with the line each came from (MoveIt reads it with
// `>>`, so a token may sit on any line; errors name the line it was on).
class SceneReader {
 public:
  SceneReader(std::istream& in, std::string source) : source_(std::move(source)) {
    for (std::string l; std::getline(in, l);) lines_.push_back(l);
  }
  SceneFile read();

 private:
  [[noreturn]] void fail(const std::string& what) const {
    // The line of the token just read (the last line once the file has ended).
    const std::size_t line = lines_.empty() ? 1 : std::min(line_, lines_.size() - 1) + 1;
    throw SceneFileError(source_ + ":" + std::to_string(line) + ": " + what);
  }
  bool at_end() {
    skip_space();
    return line_ >= lines_.size();
  }
  void skip_space() {
    while (line_ < lines_.size()) {
      const std::string& l = lines_[line_];
      while (col_ < l.size() && std::isspace(static_cast<unsigned char>(l[col_]))) ++col_;
      if (col_ < l.size()) return;
      ++line_, col_ = 0;
    }
  }
  std::string token(const std::string& what) {
    if (at_end()) fail(what + ": missing (the file ends first)");
    const std::string& l = lines_[line_];
    const std::size_t start = col_;
    while (col_ < l.size() && !std::isspace(static_cast<unsigned char>(l[col_]))) ++col_;
    return l.substr(start, col_ - start);
  }
  std::string rest_of_line() {
    const std::string rest = line_ < lines_.size() ? trimmed(lines_[line_].substr(col_)) : "";
    ++line_, col_ = 0;
    return rest;
  }
  double number(const std::string& what);
  std::size_t count(const std::string& what, std::size_t largest);
  Transform pose(const std::string& what);
  ObjectShape shape(const std::string& what);
  SceneObject object(bool new_format);
  bool new_format() const;

  std::vector<std::string> lines_;
  std::string source_;
  std::unordered_map<std::string, int> lines_of_ids_;  // each id's first line
  std::size_t line_ = 0, col_ = 0;  // the next token is at or after lines_[line_][col_]
};

double SceneReader::number(const std::string& what) {
  const std::string t = token(what);
  // Decimal only (strtod would also take hexadecimal, "nan" and "inf").
  const bool decimal = t.find_first_not_of("0123456789+-.eE") == std::string::npos;
  char* end = nullptr;
  const double v = decimal ? std::strtod(t.c_str(), &end) : 0.0;
  if (!decimal || end != t.c_str() + t.size()) fail(what + ": '" + t + "' is not a number");
  if (!std::isfinite(v)) fail(what + ": '" + t + "' is not finite");
  return v;
}

std::size_t SceneReader::count(const std::string& what, std::size_t largest) {
  const std::string t = token(what);
  if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos || t.size() > 12) {
    fail(what + ": '" + t + "' is not a whole number");
  }
  const std::size_t n = std::stoull(t);
  if (n > largest) fail(what + ": " + t + " is more than " + std::to_string(largest));
  return n;
}

Transform SceneReader::pose(const std::string& what) {
  Vec3 t;
  for (int i = 0; i < 3; ++i) t[i] = number(what + " position " + "xyz"[i]);
  if (t.cwiseAbs().maxCoeff() > kLargest) fail(what + ": position beyond 1e5 m");
  double q[4];
  for (int i = 0; i < 4; ++i) q[i] = number(what + " orientation " + "xyzw"[i]);
  const Eigen::Quaterniond r(q[3], q[0], q[1], q[2]);
  // MoveIt writes six significant digits: a unit quaternion reads back within about 1e-6.
  if (std::abs(r.norm() - 1.0) > 1e-3) {
    std::ostringstream norm;
    norm << r.norm();
    fail(what + ": orientation is not a unit quaternion (norm " + norm.str() + ")");
  }
  return {r.normalized().toRotationMatrix(), t};
}

ObjectShape SceneReader::shape(const std::string& what) {
  const std::string type = token(what + " type");
  auto positive = [&](const std::string& field) {
    const double v = number(what + " (" + type + ") " + field);
    if (!(v > 0.0) || v > kLargest) fail(what + " (" + type + ") " + field + " is not a positive number up to 1e5 m");
    return v;
  };
  if (type == "box") {
    Vec3 size;
    for (int i = 0; i < 3; ++i) size[i] = positive("size " + std::to_string(i + 1));
    return ObjectShape::box(size);
  }
  if (type == "sphere") return ObjectShape::sphere(positive("radius"));
  if (type == "cylinder" || type == "cone") {
    const double radius = positive("radius"), length = positive("length");
    return type == "cylinder" ? ObjectShape::cylinder(radius, length) : ObjectShape::cone(radius, length);
  }
  if (type == "mesh") {
    TriangleMesh m;
    const std::size_t vertices = count(what + " (mesh) vertex count", 10'000'000);
    const std::size_t triangles = count(what + " (mesh) triangle count", 10'000'000);
    for (std::size_t v = 0; v < vertices; ++v) {
      Vec3 p;
      for (int i = 0; i < 3; ++i) p[i] = number(what + " (mesh) vertex " + std::to_string(v));
      if (p.cwiseAbs().maxCoeff() > kLargest) fail(what + " (mesh) vertex " + std::to_string(v) + " beyond 1e5 m");
      m.vertices.push_back(p);
    }
    for (std::size_t t = 0; t < triangles; ++t) {
      std::array<std::int32_t, 3> tri{};
      for (int i = 0; i < 3; ++i) {
        const std::string field = what + " (mesh) triangle " + std::to_string(t);
        const std::size_t index = count(field, 10'000'000);
        if (index >= vertices) fail(field + ": vertex " + std::to_string(index) + " of " + std::to_string(vertices));
        tri[i] = static_cast<std::int32_t>(index);
      }
      m.triangles.push_back(tri);
    }
    if (m.triangles.empty()) fail(what + " (mesh): no triangle");
    return ObjectShape::triangles(std::move(m));
  }
  if (type == "plane") fail(what + ": a plane (infinite) is not supported");
  fail(what + ": unknown shape type '" + type + "' (box, sphere, cylinder, cone or mesh)");
}

SceneObject SceneReader::object(bool new_format) {
  SceneObject o;
  o.id = rest_of_line();
  --line_;  // errors about the id name its line
  o.line = static_cast<int>(line_) + 1;
  if (o.id.empty()) fail("an object without an id");
  if (const std::string problem = object_id_problem(o.id); !problem.empty()) fail("object " + problem);
  ++line_;
  const std::string what = "object '" + o.id + "'";
  if (new_format) o.pose = pose(what + " pose");
  const std::size_t shapes = count(what + " shape count", 1'000'000);
  if (shapes == 0) fail(what + ": no shape");
  for (std::size_t k = 0; k < shapes; ++k) {
    const std::string part = what + " shape " + std::to_string(k + 1);
    SceneShape s;
    s.shape = shape(part);
    s.pose = pose(part + " pose");
    for (int i = 0; i < 4; ++i) number(part + " colour " + "rgba"[i]);
    o.shapes.push_back(std::move(s));
  }
  if (new_format) {
    const std::size_t subframes = count(what + " subframe count", 1'000'000);
    for (std::size_t k = 0; k < subframes; ++k) {
      const std::string name = token(what + " subframe " + std::to_string(k + 1) + " name");
      o.subframes.emplace_back(name, pose(what + " subframe '" + name + "' pose"));
    }
  }
  return o;
}

// MoveIt's test: the line after the first object's `*` line holds a position (three numbers
// with spaces: the newer format, with object poses and subframes) or a shape count.
bool SceneReader::new_format() const {
  for (std::size_t l = 1; l < lines_.size(); ++l) {
    if (lines_[l].empty() || lines_[l][0] != '*') continue;
    return l + 1 < lines_.size() && trimmed(lines_[l + 1]).find(' ') != std::string::npos;
  }
  return true;
}

SceneFile SceneReader::read() {
  SceneFile scene;
  if (lines_.empty()) fail("empty: a scene starts with its name");
  scene.name = trimmed(lines_[0]);
  line_ = 1;
  const bool format = new_format();
  for (;;) {
    const std::string marker = token("an object ('*') or the end ('.')");
    if (marker == ".") break;
    if (marker != "*") fail("'" + marker + "' where an object ('* id') or the end ('.') belongs");
    SceneObject o = object(format);
    // A second entry of an id adds its shapes to the object (scene_file.h): kept as read, merged
    // where the scene is applied. Found by a hash: a scene of n objects reads in n steps, not n^2.
    const auto [first, added] = lines_of_ids_.emplace(o.id, o.line);
    if (!added) {
      scene.warnings.push_back(source_ + ":" + std::to_string(o.line) + ": object '" + o.id + "' is also at line " +
                               std::to_string(first->second) + ": its shapes are added to that object's (MoveIt 1.1.12 and later "
                               "would keep only these)");
    }
    scene.objects.push_back(std::move(o));
  }
  return scene;
}

void write_pose(std::ostream& out, const Transform& t) {
  const Eigen::Quaterniond q(t.R);
  out << t.t.x() << " " << t.t.y() << " " << t.t.z() << "\n" << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
}

void write_shape(std::ostream& out, const ObjectShape& s) {
  switch (s.kind) {
    case ObjectShape::Kind::kBox: out << "box\n" << s.size.x() << " " << s.size.y() << " " << s.size.z() << "\n"; return;
    case ObjectShape::Kind::kSphere: out << "sphere\n" << s.radius << "\n"; return;
    case ObjectShape::Kind::kCylinder: out << "cylinder\n" << s.radius << " " << s.length << "\n"; return;
    case ObjectShape::Kind::kCone: out << "cone\n" << s.radius << " " << s.length << "\n"; return;
    case ObjectShape::Kind::kMesh:
      out << "mesh\n" << s.mesh->vertices.size() << " " << s.mesh->triangles.size() << "\n";
      for (const Vec3& v : s.mesh->vertices) out << v.x() << " " << v.y() << " " << v.z() << "\n";
      for (const auto& t : s.mesh->triangles) out << t[0] << " " << t[1] << " " << t[2] << "\n";
      return;
    case ObjectShape::Kind::kCapsule: break;
  }
  throw std::invalid_argument("a capsule has no MoveIt .scene form");
}

}  // namespace

SceneFile read_scene_text(std::istream& in, const std::string& source) { return SceneReader(in, source).read(); }

SceneFile read_scene_file(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw SceneFileError(path + ": no such file");
  if (!std::filesystem::is_regular_file(status)) throw SceneFileError(path + ": not a regular file");
  if (std::filesystem::file_size(path, ec) > kLargestFile) throw SceneFileError(path + ": over 64 MiB");
  std::ifstream in(path);
  if (!in) throw SceneFileError(path + ": cannot be read");
  const std::string ext = std::filesystem::path(path).extension().string();
  return ext == ".yaml" || ext == ".yml" ? read_scene_yaml(in, path) : read_scene_text(in, path);
}

void write_scene_file(const SceneFile& scene, const std::string& path) {
  std::ostringstream text;  // written whole, or not at all
  const std::string ext = std::filesystem::path(path).extension().string();
  try {
    ext == ".yaml" || ext == ".yml" ? write_scene_yaml(scene, text) : write_scene_text(scene, text);
  } catch (const std::invalid_argument& e) {
    throw SceneFileError(path + ": the scene cannot be written: " + e.what());
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out || !(out << text.str()) || !out.flush()) throw SceneFileError("cannot write '" + path + "'");
}

void write_scene_text(const SceneFile& scene, std::ostream& out) {
  if (scene.is_diff) throw std::invalid_argument("a diff (is_diff) has no .scene form: write it as YAML");
  std::ostringstream text;  // nothing reaches `out` if a shape cannot be written
  text << std::setprecision(17);
  text << scene.name << "\n";
  for (const SceneObject& o : scene.objects) {
    text << "* " << o.id << "\n";
    write_pose(text, o.pose);
    text << o.shapes.size() << "\n";
    for (const SceneShape& s : o.shapes) {
      write_shape(text, s.shape);
      write_pose(text, s.pose);
      text << "0 0 0 0\n";  // no colour
    }
    text << o.subframes.size() << "\n";
    for (const auto& [name, pose] : o.subframes) {
      text << name << "\n";
      write_pose(text, pose);
    }
  }
  text << ".\n";
  out << text.str();
}

}  // namespace bvh_collision
