#include "bvh_collision/robot/mesh_loader.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <tinyxml2.h>

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <vector>

#include "bvh_collision/robot/urdf_validation.h"

namespace bvh_collision {
namespace {

Mat3 rotation_part(const aiMatrix4x4& m, Vec3& translation) {
  Mat3 r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
    translation[i] = m[i][3];
  }
  return r;
}

void append_node(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent, bool is_root,
                 const Vec3& scale, TriangleMesh& out) {
  // ROS convention for Collada: the root node's transform (up-axis conversion) is ignored.
  const aiMatrix4x4 transform = is_root ? parent : parent * node->mTransformation;
  Vec3 t;
  const Mat3 r = rotation_part(transform, t);
  for (unsigned m = 0; m < node->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[m]];
    const auto base = static_cast<std::int32_t>(out.vertices.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      out.vertices.push_back((r * Vec3(p.x, p.y, p.z) + t).cwiseProduct(scale));
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not collision geometry
      for (unsigned k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices) {
          throw MeshLoadError("face " + std::to_string(f) + " names vertex " + std::to_string(face.mIndices[k]) +
                              " of " + std::to_string(mesh->mNumVertices));
        }
      }
      out.triangles.push_back({base + static_cast<std::int32_t>(face.mIndices[0]),
                               base + static_cast<std::int32_t>(face.mIndices[1]),
                               base + static_cast<std::int32_t>(face.mIndices[2])});
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) {
    append_node(scene, node->mChildren[c], transform, false, scale, out);
  }
}

// What assimp returned must be a usable surface: triangles, and every vertex they use finite
// (one NaN vertex reached undefined behaviour in the hierarchy builder).
void check_loaded(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) throw MeshLoadError("holds no triangles");
  bool has_area = false;
  for (const auto& t : mesh.triangles) {
    for (const std::int32_t v : t) {
      const Vec3& p = mesh.vertices[v];
      if (!p.allFinite()) {
        throw MeshLoadError("vertex " + std::to_string(v) + " is not finite (" + std::to_string(p.x()) + " " +
                            std::to_string(p.y()) + " " + std::to_string(p.z()) + ")");
      }
    }
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    has_area = has_area || (b - a).cross(c - a).squaredNorm() > 0.0;
  }
  // Zero-area triangles still collide, but a mesh of nothing else is a broken file.
  if (!has_area) throw MeshLoadError("has no triangle of non-zero area");
}

// ------------------------------------------------------------- Collada structure, before import

// Whole non-negative integers below 2^31, or nothing.
std::optional<std::vector<long long>> whole_numbers(const char* text) {
  std::vector<long long> out;
  std::istringstream words(text ? text : "");
  std::string word;
  while (words >> word) {
    if (word.size() > 10 || word.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
    const long long v = std::stoll(word);
    if (v >= (1LL << 31)) return std::nullopt;
    out.push_back(v);
  }
  return out;
}

std::size_t token_count(const char* text) {
  std::istringstream words(text ? text : "");
  std::size_t n = 0;
  for (std::string w; words >> w;) ++n;
  return n;
}

// An integer attribute (with a default when absent), checked to be whole and non-negative.
long long whole_attribute(const tinyxml2::XMLElement& e, const char* name, long long fallback) {
  const char* text = e.Attribute(name);
  if (text == nullptr) return fallback;
  const auto v = whole_numbers(text);
  if (!v || v->size() != 1) {
    throw MeshLoadError(std::string("<") + e.Name() + "> (line " + std::to_string(e.GetLineNum()) + ") " + name + "='" +
                        text + "' is not a whole number from 0 to 2^31 - 1");
  }
  return (*v)[0];
}

// assimp trusts a Collada file's counts, strides, offsets and index lists: a stride of 10^6
// crashed it, a non-integer index made it allocate without end, and counts beyond an array or a
// negative offset were read as if valid. Every one of them is checked here first.
class ColladaCheck {
 public:
  void run(const tinyxml2::XMLElement& e) {
    const std::string name = e.Name();
    if (name == "float_array" || name == "int_array") array(e);
    if (name == "p" || name == "vcount" || name == "v") indices(e);
    if (name == "input") {
      whole_attribute(e, "offset", 0);
      whole_attribute(e, "set", 0);
    }
    if (name == "accessor") accessors_.push_back(&e);
    const tinyxml2::XMLElement* outer = node_;
    if (name == "node") enter_node(e);
    if (name == "instance_node" && node_ && e.Attribute("url") && e.Attribute("url")[0] == '#') {
      instances_[node_].push_back(e.Attribute("url") + 1);
    }
    for (const tinyxml2::XMLElement* c = e.FirstChildElement(); c != nullptr; c = c->NextSiblingElement()) run(*c);
    node_ = outer;
  }
  // A node that instances itself, directly or through others, sent assimp into endless
  // recursion (a stack overflow); nodes instanced over a million times would exhaust memory.
  void check_node_instances() {
    std::map<const tinyxml2::XMLElement*, int> state;  // 1: being expanded, 2: done
    std::map<const tinyxml2::XMLElement*, double> copies;
    for (const auto& [node, unused] : children_) expand(node, state, copies, 0);
  }
  void check_accessors() const {
    for (const tinyxml2::XMLElement* a : accessors_) {
      const long long count = whole_attribute(*a, "count", 0), stride = whole_attribute(*a, "stride", 1),
                      offset = whole_attribute(*a, "offset", 0);
      const std::string where = "<accessor> (line " + std::to_string(a->GetLineNum()) + ")";
      if (stride < 1) throw MeshLoadError(where + " has stride " + std::to_string(stride));
      const char* source = a->Attribute("source");
      const auto it = source && *source == '#' ? arrays_.find(source + 1) : arrays_.end();
      if (it == arrays_.end()) continue;  // assimp reports sources it cannot find
      if (offset + count * stride > it->second) {
        throw MeshLoadError(where + " reads " + std::to_string(offset + count * stride) + " values of an array of " +
                            std::to_string(it->second));
      }
    }
  }

 private:
  void array(const tinyxml2::XMLElement& e) {
    const long long count = whole_attribute(e, "count", -1);
    const std::size_t tokens = token_count(e.GetText());
    if (count >= 0 && static_cast<std::size_t>(count) != tokens) {
      throw MeshLoadError(std::string("<") + e.Name() + "> (line " + std::to_string(e.GetLineNum()) + ") has count " +
                          std::to_string(count) + " but " + std::to_string(tokens) + " values");
    }
    if (const char* id = e.Attribute("id")) arrays_[id] = static_cast<long long>(tokens);
  }
  void indices(const tinyxml2::XMLElement& e) const {
    if (!whole_numbers(e.GetText())) {
      throw MeshLoadError(std::string("<") + e.Name() + "> (line " + std::to_string(e.GetLineNum()) +
                          ") holds a value that is not a whole number from 0 to 2^31 - 1");
    }
  }
  void enter_node(const tinyxml2::XMLElement& e) {
    if (node_) children_[node_].push_back(&e);
    children_[&e];
    if (const char* id = e.Attribute("id")) nodes_by_id_[id] = &e;
    node_ = &e;
  }
  // The number of node copies below `node` once instances are expanded (with a cycle check).
  double expand(const tinyxml2::XMLElement* node, std::map<const tinyxml2::XMLElement*, int>& state,
                std::map<const tinyxml2::XMLElement*, double>& copies, int depth) {
    if (state[node] == 2) return copies[node];
    const std::string where = "<node> (line " + std::to_string(node->GetLineNum()) + ")";
    if (state[node] == 1) throw MeshLoadError(where + " instances itself");
    if (depth > 256) throw MeshLoadError(where + " lies more than 256 nodes and instances deep");
    state[node] = 1;
    double n = 1.0;
    for (const tinyxml2::XMLElement* c : children_[node]) n += expand(c, state, copies, depth + 1);
    for (const std::string& id : instances_[node]) {
      const auto it = nodes_by_id_.find(id);
      if (it != nodes_by_id_.end()) n += expand(it->second, state, copies, depth + 1);
    }
    if (n > 1e6) throw MeshLoadError(where + " expands to over a million node copies");
    state[node] = 2;
    return copies[node] = n;
  }

  std::map<std::string, long long> arrays_;
  std::vector<const tinyxml2::XMLElement*> accessors_;
  const tinyxml2::XMLElement* node_ = nullptr;  // the innermost <node> being read
  std::map<const tinyxml2::XMLElement*, std::vector<const tinyxml2::XMLElement*>> children_;
  std::map<const tinyxml2::XMLElement*, std::vector<std::string>> instances_;
  std::map<std::string, const tinyxml2::XMLElement*> nodes_by_id_;
};

// ------------------------------------------------------------ ASCII STL grammar, before import

// assimp reads a truncated ASCII STL, a facet of four vertices or a missing `endloop` as far as
// it makes sense of them and drops the rest without a word; the grammar is checked here first.
class AsciiStlCheck {
 public:
  explicit AsciiStlCheck(std::istream& in) : in_(in) {}
  void run() {
    expect("solid");
    skip_line();
    for (;;) {
      const std::string w = word();
      if (w == "endsolid") {
        skip_line();
        if (word().empty()) return;  // another solid may follow
        unread_ = true;
        expect("solid");
        skip_line();
        continue;
      }
      if (w != "facet") fail("'facet' or 'endsolid'", w);
      expect("normal");
      numbers(3);
      expect("outer");
      expect("loop");
      for (int k = 0; k < 3; ++k) {
        expect("vertex");
        numbers(3);
      }
      expect("endloop");
      expect("endfacet");
    }
  }

 private:
  std::string word() {
    if (unread_) {
      unread_ = false;
      return last_;
    }
    last_.clear();
    in_ >> last_;
    std::transform(last_.begin(), last_.end(), last_.begin(), [](unsigned char c) { return std::tolower(c); });
    return last_;
  }
  void skip_line() {
    std::string rest;
    std::getline(in_, rest);
  }
  [[noreturn]] void fail(const std::string& wanted, const std::string& found) const {
    throw MeshLoadError("ASCII STL: expected " + wanted + ", found " + (found.empty() ? "the end of the file" : "'" + found + "'"));
  }
  void expect(const char* keyword) {
    const std::string w = word();
    if (w != keyword) fail(std::string("'") + keyword + "'", w);
  }
  void numbers(int n) {
    for (int i = 0; i < n; ++i) {
      const std::string w = word();
      const std::optional<double> v = parse_decimal(w);
      if (!v) fail("a number", w);
      if (!std::isfinite(*v)) throw MeshLoadError("ASCII STL: '" + w + "' is not a finite number");
    }
  }
  std::istream& in_;
  std::string last_;
  bool unread_ = false;
};

// An .stl file that starts with "solid" and is not a binary STL by its size (84 + 50 n bytes).
bool is_ascii_stl(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".stl") return false;
  std::ifstream in(path, std::ios::binary);
  char header[84] = {};
  in.read(header, sizeof header);
  const std::size_t got = static_cast<std::size_t>(in.gcount());
  std::size_t start = 0;
  while (start < got && std::isspace(static_cast<unsigned char>(header[start]))) ++start;
  if (got - start < 5 || std::strncmp(header + start, "solid", 5) != 0) return false;
  if (got == sizeof header) {
    std::uint32_t n = 0;
    std::memcpy(&n, header + 80, 4);
    std::error_code ec;
    if (std::filesystem::file_size(path, ec) == 84 + 50 * std::uintmax_t(n)) return false;  // binary after all
  }
  return true;
}

void check_ascii_stl(const std::string& path) {
  std::ifstream in(path);
  try {
    AsciiStlCheck(in).run();
  } catch (const MeshLoadError& e) {
    throw MeshLoadError("mesh file '" + path + "': " + e.what());
  }
}

bool is_collada(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".dae";
}

void check_collada(const std::string& path) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS) {
    throw MeshLoadError("mesh file '" + path + "' is not well-formed XML (line " + std::to_string(doc.ErrorLineNum()) + ")");
  }
  try {
    ColladaCheck check;
    if (doc.RootElement()) check.run(*doc.RootElement());
    check.check_accessors();
    check.check_node_instances();
  } catch (const MeshLoadError& e) {
    throw MeshLoadError("mesh file '" + path + "': " + e.what());
  }
}

// The import itself, in whatever process runs it.
TriangleMesh import_mesh(const std::string& path, const Vec3& scale) {
  if (!std::filesystem::is_regular_file(path)) {
    throw MeshLoadError("mesh file '" + path + "' does not exist or is not a file");
  }
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) > kMaxMeshFileBytes || ec) {
    throw MeshLoadError("mesh file '" + path + "' is larger than " + std::to_string(kMaxMeshFileBytes >> 20) + " MiB");
  }
  if (!scale.allFinite() || (scale.array() == 0.0).any()) {
    throw MeshLoadError("mesh file '" + path + "': scale must be finite and non-zero");
  }
  if (is_collada(path)) check_collada(path);
  if (is_ascii_stl(path)) check_ascii_stl(path);
  Assimp::Importer importer;
  // Keep every triangle: no degenerate or invalid-data removal (a zero-area triangle still collides).
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (scene == nullptr || scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    throw MeshLoadError("mesh file '" + path + "' cannot be read: " + importer.GetErrorString());
  }
  TriangleMesh mesh;
  try {
    append_node(scene, scene->mRootNode, aiMatrix4x4(), true, scale, mesh);
    check_loaded(mesh);
  } catch (const MeshLoadError& e) {
    throw MeshLoadError("mesh file '" + path + "': " + e.what());
  }
  return mesh;
}

// ------------------------------------------------------------------ the import in a child

bool write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// The child's answer: 'M', vertex and triangle counts, then the raw arrays; or 'E' and a message.
std::string encode(const TriangleMesh& m) {
  const std::uint64_t counts[2] = {m.vertices.size(), m.triangles.size()};
  std::string out = "M";
  out.append(reinterpret_cast<const char*>(counts), sizeof counts);
  for (const Vec3& v : m.vertices) out.append(reinterpret_cast<const char*>(v.data()), 3 * sizeof(double));
  for (const auto& t : m.triangles) out.append(reinterpret_cast<const char*>(t.data()), 3 * sizeof(std::int32_t));
  return out;
}

std::optional<TriangleMesh> decode(const std::string& in) {
  std::uint64_t counts[2];
  if (in.size() < 1 + sizeof counts || in[0] != 'M') return std::nullopt;
  std::memcpy(counts, in.data() + 1, sizeof counts);
  const std::size_t need = 1 + sizeof counts + counts[0] * 3 * sizeof(double) + counts[1] * 3 * sizeof(std::int32_t);
  if (counts[0] > in.size() || counts[1] > in.size() || in.size() != need) return std::nullopt;
  TriangleMesh m;
  m.vertices.resize(counts[0]);
  m.triangles.resize(counts[1]);
  const char* p = in.data() + 1 + sizeof counts;
  for (Vec3& v : m.vertices) std::memcpy(v.data(), p, 3 * sizeof(double)), p += 3 * sizeof(double);
  for (auto& t : m.triangles) std::memcpy(t.data(), p, 3 * sizeof(std::int32_t)), p += 3 * sizeof(std::int32_t);
  return m;
}

// The child's resident memory (bytes), from /proc; 0 when unknown.
std::size_t resident_bytes(pid_t pid) {
  std::ifstream statm("/proc/" + std::to_string(pid) + "/statm");
  std::size_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

// Reads the child's answer until it closes the pipe, killing it past the memory or time limit.
// Returns the reason it was killed, or empty.
std::string collect(int fd, pid_t pid, std::size_t baseline, const MeshImportLimits& limits, std::string& data) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(limits.seconds);
  char buffer[1 << 16];
  for (;;) {
    if (std::chrono::steady_clock::now() >= deadline) {
      ::kill(pid, SIGKILL);
      return "it could not be loaded within " + std::to_string(static_cast<long>(limits.seconds)) + " s";
    }
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, 20);
    if (ready > 0) {
      const ssize_t n = ::read(fd, buffer, sizeof buffer);
      if (n == 0) return "";
      if (n > 0) data.append(buffer, static_cast<std::size_t>(n));
      if (n < 0 && errno != EINTR) return "";
    }
    if (resident_bytes(pid) > baseline + limits.memory_bytes) {
      ::kill(pid, SIGKILL);
      return "it could not be loaded within " + std::to_string(limits.memory_bytes >> 20) + " MiB";
    }
  }
}

}  // namespace

namespace {

// The import in a child process (see MeshImportLimits), unscaled.
TriangleMesh import_isolated(const std::string& path, const MeshImportLimits& limits) {
  int fd[2];
  if (::pipe(fd) != 0) throw MeshLoadError("mesh file '" + path + "': no pipe for the importer");
  // The child starts with the parent's pages: its own use is what it adds to them.
  const std::size_t baseline = resident_bytes(::getpid());
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd[0]);
    ::close(fd[1]);
    throw MeshLoadError("mesh file '" + path + "': cannot start the importer");
  }
  if (pid == 0) {  // the child: import, answer, and leave without running the parent's exit handlers
    ::close(fd[0]);
    std::string out;
    try {
      out = encode(import_mesh(path, Vec3::Ones()));
    } catch (const std::exception& e) {
      out = std::string("E") + e.what();
    }
    write_all(fd[1], out.data(), out.size());
    ::_exit(0);
  }
  ::close(fd[1]);
  std::string data;
  const std::string killed = collect(fd[0], pid, baseline, limits, data);
  ::close(fd[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!killed.empty()) throw MeshLoadError("mesh file '" + path + "': " + killed);
  if (!data.empty() && data[0] == 'E') throw MeshLoadError(data.substr(1));
  if (WIFSIGNALED(status)) {
    throw MeshLoadError("mesh file '" + path + "' crashed the importer (" + strsignal(WTERMSIG(status)) + ")");
  }
  if (auto mesh = decode(data)) return std::move(*mesh);
  throw MeshLoadError("mesh file '" + path + "': the importer gave no answer");
}

// Imported files by path, size and modification time: a process that loads the same robot
// again (tests, a node reloading) imports each file once. Bounded: cleared past 4 M triangles.
class ImportCache {
 public:
  std::shared_ptr<const TriangleMesh> find(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = meshes_.find(key);
    return it == meshes_.end() ? nullptr : it->second;
  }
  void add(const std::string& key, std::shared_ptr<const TriangleMesh> mesh) {
    std::lock_guard<std::mutex> lock(mutex_);
    triangles_ += mesh->triangles.size();
    if (triangles_ > kMaxTriangles) {
      meshes_.clear();
      triangles_ = mesh->triangles.size();
    }
    meshes_[key] = std::move(mesh);
  }

 private:
  static constexpr std::size_t kMaxTriangles = std::size_t(4) << 20;
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<const TriangleMesh>> meshes_;
  std::size_t triangles_ = 0;
};

std::string cache_key(const std::string& path, const MeshImportLimits& limits) {
  std::error_code ec;
  const auto canonical = std::filesystem::weakly_canonical(path, ec).string();
  const auto size = std::filesystem::file_size(path, ec);
  const auto time = std::filesystem::last_write_time(path, ec).time_since_epoch().count();
  return canonical + "|" + std::to_string(size) + "|" + std::to_string(time) + "|" +
         std::to_string(limits.memory_bytes) + "|" + std::to_string(limits.seconds);
}

}  // namespace

TriangleMesh load_mesh(const std::string& path, const Vec3& scale, const MeshImportLimits& limits) {
  if (!scale.allFinite() || (scale.array() == 0.0).any()) {
    throw MeshLoadError("mesh file '" + path + "': scale must be finite and non-zero");
  }
  static ImportCache cache;
  const std::string key = cache_key(path, limits);
  std::shared_ptr<const TriangleMesh> unscaled = limits.isolated ? cache.find(key) : nullptr;
  if (!limits.isolated) {
    unscaled = std::make_shared<const TriangleMesh>(import_mesh(path, Vec3::Ones()));
  } else if (!unscaled) {
    unscaled = std::make_shared<const TriangleMesh>(import_isolated(path, limits));
    cache.add(key, unscaled);
  }
  TriangleMesh mesh = *unscaled;
  for (Vec3& v : mesh.vertices) {
    v = v.cwiseProduct(scale);
    if (!v.allFinite()) throw MeshLoadError("mesh file '" + path + "': a vertex scaled is not finite");
  }
  if (scale.x() * scale.y() * scale.z() < 0.0) {
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);  // mirrored: keep outward winding
  }
  return mesh;
}

}  // namespace bvh_collision
