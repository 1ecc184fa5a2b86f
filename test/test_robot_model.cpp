// The robot layer's loader and kinematics: every robot of ../shared/robots loads with the
// manifest's meshes (triangle counts, bounding boxes, files read once); forward kinematics
// equals KDL's on random configurations; a project-written URDF exercises the loader's edge cases.
#include <gtest/gtest.h>

#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/bvh/bounding_volumes.h"
#include "bvh_collision/geometry/sin_cos.h"
#include "bvh_collision/robot/mesh_loader.h"
#include "bvh_collision/robot/robot_model.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

RobotModel load_robot(const std::string& robot) {
  const std::string dir = test::robots_dir() + "/" + robot;
  return RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
}

TEST(RobotModel, EveryRealRobotLoadsTheManifestMeshes) {
  BVH_REQUIRE_ROBOTS();
  std::ifstream in(test::robots_dir() + "/MANIFEST.json");
  const json manifest = json::parse(in);
  for (const auto& [robot, expected] : manifest.items()) {
    SCOPED_TRACE(robot);
    const RobotModel model = load_robot(robot);
    EXPECT_EQ(model.links().size(), expected["links"].get<std::size_t>());
    EXPECT_EQ(model.joints().size(), expected["joints"].get<std::size_t>());
    EXPECT_EQ(model.mesh_files_read(), expected["collision_meshes"].size()) << "each file read once";
    std::size_t elements = 0, instanced = 0;
    std::map<std::string, const CollisionElement*> by_uri;
    for (const RobotLink& link : model.links()) {
      elements += link.collision.size();
      for (const CollisionElement& e : link.collision) {
        if (e.shape != CollisionElement::Shape::kMesh) continue;
        instanced += e.mesh->triangles.size();
        by_uri[e.source.substr(6, e.source.size() - 7)] = &e;  // strip "mesh '" and "'"
      }
    }
    EXPECT_EQ(elements, expected["collision_elements"].get<std::size_t>());
    EXPECT_EQ(instanced, expected["collision_triangles_instanced"].get<std::size_t>());
    for (const auto& mesh : expected["collision_meshes"]) {
      const std::string uri = mesh["uri"];
      ASSERT_TRUE(by_uri.count(uri)) << uri;
      const TriangleMesh& m = *by_uri.at(uri)->mesh;
      EXPECT_EQ(m.triangles.size(), mesh["triangles"].get<std::size_t>()) << uri;
      Aabb box;
      for (const auto& t : m.triangles) {
        for (int k = 0; k < 3; ++k) box.extend(m.vertices[t[k]]);
      }
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(box.min[k], mesh["bbox_min"][k].get<double>(), 1e-6) << uri;
        EXPECT_NEAR(box.max[k], mesh["bbox_max"][k].get<double>(), 1e-6) << uri;
      }
    }
  }
}

TEST(RobotModel, ForwardKinematicsEqualsKdlOnEveryRobot) {
  BVH_REQUIRE_ROBOTS();
  std::mt19937_64 rng(3);
  for (const char* robot : {"panda", "ur5e", "pr2", "abb_irb2400", "panda_capsules", "solo"}) {
    SCOPED_TRACE(robot);
    const auto urdf = load_robot_description_file(test::robots_dir() + "/" + robot + "/robot.urdf");
    const RobotModel model = RobotModel::from_urdf(*urdf, PackageResolver({test::robots_dir() + "/" + robot}));
    KDL::Tree tree;
    ASSERT_TRUE(kdl_parser::treeFromUrdfModel(*urdf, tree));
    KDL::TreeFkSolverPos_recursive solver(tree);
    std::vector<Transform> poses, planned;
    // The precomputed plan, for every link and for the links with geometry only (fixed joints
    // folded away, axis-aligned rotations special-cased): the same poses as KDL's.
    std::vector<bool> with_geometry(model.links().size());
    for (std::size_t l = 0; l < with_geometry.size(); ++l) with_geometry[l] = !model.links()[l].collision.empty();
    const KinematicsPlan all_links(model, std::vector<bool>(model.links().size(), true));
    const KinematicsPlan geometry_links(model, with_geometry);
    EXPECT_LE(geometry_links.steps(), all_links.steps());
    for (int sample = 0; sample < 200; ++sample) {
      std::vector<double> state(model.variable_count());
      for (std::size_t v = 0; v < state.size(); ++v) {
        const RobotJoint& j = model.joints()[model.joint_index(model.variable_names()[v])];
        const double lo = j.bounded ? j.lower : -M_PI, hi = j.bounded ? j.upper : M_PI;
        state[v] = std::uniform_real_distribution<double>(lo, hi)(rng);
      }
      forward_kinematics(model, state.data(), poses);
      // KDL knows nothing of mimic joints: give each KDL joint the value our model derives.
      KDL::JntArray q(tree.getNrOfJoints());
      for (const auto& [name, element] : tree.getSegments()) {
        const KDL::Segment& seg = GetTreeElementSegment(element);
        if (seg.getJoint().getType() == KDL::Joint::None) continue;
        const RobotJoint& j = model.joints()[model.joint_index(seg.getJoint().getName())];
        const double value = j.variable >= 0 ? state[j.variable]
                                             : j.multiplier * state[model.joints()[j.mimic].variable] + j.offset;
        q(GetTreeElementQNr(element)) = value;
      }
      const KinematicsPlan& plan = sample % 2 ? all_links : geometry_links;
      planned.assign(model.links().size(), Transform::Translation(Vec3::Constant(NAN)));
      plan.compute(state.data(), planned);
      for (std::size_t l = 0; l < model.links().size(); ++l) {
        KDL::Frame frame;
        ASSERT_GE(solver.JntToCart(q, frame, model.links()[l].name), 0) << model.links()[l].name;
        const bool check_plan = sample % 2 || with_geometry[l];
        for (int r = 0; r < 3; ++r) {
          EXPECT_NEAR(poses[l].t[r], frame.p(r), 1e-9) << model.links()[l].name;
          if (check_plan) {
            EXPECT_NEAR(planned[l].t[r], frame.p(r), 1e-9) << "plan " << model.links()[l].name;
          }
          for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(poses[l].R(r, c), frame.M(r, c), 1e-9) << model.links()[l].name;
            if (check_plan) {
              EXPECT_NEAR(planned[l].R(r, c), frame.M(r, c), 1e-9) << "plan " << model.links()[l].name;
            }
          }
        }
      }
      if (HasFailure()) return;
    }
  }
}

// ---------------------------------------------------------------- a project-written URDF

// A binary STL of a unit box with corner (0, 0, 0) and (1, 2, 3) (outward winding).
void write_stl(const fs::path& path, float poison = 0.0f) {
  const TriangleMesh box = box_mesh(Vec3(1, 2, 3));
  std::ofstream out(path, std::ios::binary);
  char header[80] = "bvh_collision test box";
  out.write(header, 80);
  const std::uint32_t n = static_cast<std::uint32_t>(box.triangles.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (std::size_t t = 0; t < n; ++t) {
    const float normal[3] = {0, 0, 0};
    out.write(reinterpret_cast<const char*>(normal), 12);
    for (int k = 0; k < 3; ++k) {
      const Vec3 v = box.vertices[box.triangles[t][k]] + Vec3(0.5, 1.0, 1.5);
      float f[3] = {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
      if (t == 5 && k == 1 && poison != 0.0f) f[0] = poison;  // one vertex of one facet
      out.write(reinterpret_cast<const char*>(f), 12);
    }
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
}

// A Collada triangle (0,0,0) (1,0,0) (0,1,0) with up_axis Z_UP and a child node translation of
// (0, 0, 5): under the ROS convention the result is the triangle moved 5 along z, not rotated.
void write_collada(const fs::path& path, const std::string& from = "", const std::string& to = "") {
  std::string text = R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="tri" name="tri"><mesh>
    <source id="tri-pos"><float_array id="tri-pos-array" count="9">0 0 0 1 0 0 0 1 0</float_array>
      <technique_common><accessor source="#tri-pos-array" count="3" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene">
    <node id="child" name="child"><translate>0 0 5</translate><instance_geometry url="#tri"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
  if (!from.empty()) text.replace(text.find(from), from.size(), to);
  std::ofstream(path) << text;
}

struct ScratchPackage {
  fs::path root;
  ScratchPackage() {
    root = fs::temp_directory_path() / ("bvh_collision_test_" + std::to_string(::getpid()));
    fs::create_directories(root / "test-meshes" / "meshes");
    std::ofstream(root / "test-meshes" / "package.xml") << "<package format=\"3\"><name>test-meshes</name></package>";
    write_stl(root / "test-meshes" / "meshes" / "box.stl");
    write_stl(root / "test-meshes" / "meshes" / "BOX_UPPER.STL");
    write_collada(root / "test-meshes" / "meshes" / "tri.dae");
    std::ofstream(root / "test-meshes" / "meshes" / "garbage.stl") << "solid nonsense\n this is not an stl\n";
  }
  ~ScratchPackage() { fs::remove_all(root); }
  RobotModel load(const std::string& links) const {
    const std::string xml = "<robot name=\"t\">" + links + "</robot>";
    return RobotModel::from_urdf(*parse_robot_description(xml), PackageResolver({root.string()}));
  }
  std::string load_error(const std::string& links) const {
    try {
      load(links);
    } catch (const RobotLoadError& e) {
      return e.what();
    }
    ADD_FAILURE() << "loading succeeded: " << links;
    return "";
  }
};

std::string mesh_link(const std::string& name, const std::string& uri, const std::string& scale = "1 1 1") {
  return "<link name=\"" + name + "\"><collision><geometry><mesh filename=\"" + uri + "\" scale=\"" + scale +
         "\"/></geometry></collision></link>";
}

TEST(RobotModel, ProjectUrdfEdgeCases) {
  const ScratchPackage pkg;
  // Several collision elements, upper-case extension, hyphenated package name, shared file.
  const RobotModel m = pkg.load(
      "<link name=\"a\"><collision><geometry><mesh filename=\"package://test-meshes/meshes/box.stl\"/></geometry></collision>"
      "<collision><origin xyz=\"0 0 1\"/><geometry><sphere radius=\"0.2\"/></geometry></collision>"
      "<collision><geometry><cylinder radius=\"0.1\" length=\"0.5\"/></geometry></collision></link>"
      "<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>" +
      mesh_link("b", "package://test-meshes/meshes/BOX_UPPER.STL") +
      "<joint name=\"k\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>" +
      mesh_link("c", "file://" + (pkg.root / "test-meshes/meshes/box.stl").string()));
  ASSERT_EQ(m.links()[m.link_index("a")].collision.size(), 3u);
  EXPECT_EQ(m.links()[m.link_index("b")].collision[0].mesh->triangles.size(), 12u);
  EXPECT_EQ(m.mesh_files_read(), 2u) << "box.stl is read once for links a and c";
  // The cylinder stays the exact shape: no polygon stands in for it.
  const CollisionElement& cyl = m.links()[m.link_index("a")].collision[2];
  EXPECT_EQ(cyl.shape, CollisionElement::Shape::kCylinder);
  EXPECT_EQ(cyl.mesh, nullptr);
  EXPECT_EQ(cyl.radius, 0.1);
  EXPECT_EQ(cyl.length, 0.5);
}

TEST(RobotModel, NegativeScaleMirrorsAndKeepsOutwardWinding) {
  const ScratchPackage pkg;
  const RobotModel m = pkg.load(mesh_link("a", "package://test-meshes/meshes/box.stl", "-1 1 1"));
  const TriangleMesh& mesh = *m.links()[0].collision[0].mesh;
  Aabb box;
  for (const Vec3& v : mesh.vertices) box.extend(v);
  EXPECT_NEAR(box.min.x(), -1.0, 1e-6);
  EXPECT_NEAR(box.max.x(), 0.0, 1e-6);
  EXPECT_TRUE(is_closed(mesh));
  // Outward winding: the signed volume (divergence theorem) is positive.
  double volume = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle tri = mesh.triangle(t);
    volume += tri[0].dot(tri[1].cross(tri[2])) / 6.0;
  }
  EXPECT_NEAR(volume, 6.0, 1e-5);
}

TEST(RobotModel, ColladaZUpFollowsTheRosConvention) {
  const ScratchPackage pkg;
  const RobotModel m = pkg.load(mesh_link("a", "package://test-meshes/meshes/tri.dae"));
  const TriangleMesh& mesh = *m.links()[0].collision[0].mesh;
  ASSERT_EQ(mesh.triangles.size(), 1u);
  for (const Vec3& v : mesh.vertices) {
    EXPECT_NEAR(v.z(), 5.0, 1e-9) << "root transform reset, child kept";
  }
}

TEST(RobotModel, LoadErrorsNameLinkElementAndFile) {
  const ScratchPackage pkg;
  std::string msg = pkg.load_error(mesh_link("arm", "package://test-meshes/meshes/missing.stl"));
  EXPECT_NE(msg.find("link 'arm'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("collision element 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("missing.stl"), std::string::npos) << msg;
  msg = pkg.load_error(mesh_link("arm", "package://test-meshes/meshes/garbage.stl"));
  EXPECT_NE(msg.find("garbage.stl"), std::string::npos) << msg;
  EXPECT_NE(msg.find("ASCII STL: expected 'facet' or 'endsolid', found 'this'"), std::string::npos) << msg;
  msg = pkg.load_error(mesh_link("arm", "http://example.com/box.stl"));
  EXPECT_NE(msg.find("unsupported URI scheme 'http://'"), std::string::npos) << msg;
  msg = pkg.load_error(mesh_link("arm", "package://no_such_package/box.stl"));
  EXPECT_NE(msg.find("package 'no_such_package' not found"), std::string::npos) << msg;
}

// Mesh content that is not a usable surface: an error naming link, element and file, never a
// crash in the hierarchy builder (one NaN vertex reached it) or a link that silently vanishes.
TEST(RobotModel, BadMeshContentIsRefusedByName) {
  const ScratchPackage pkg;
  const fs::path dir = pkg.root / "test-meshes" / "meshes";
  write_stl(dir / "nan_binary.stl", std::numeric_limits<float>::quiet_NaN());
  write_stl(dir / "inf_binary.stl", std::numeric_limits<float>::infinity());
  std::ofstream(dir / "nan_ascii.stl") << "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\n"
                                          "vertex 0 1 0\nendloop\nendfacet\nendsolid s\n";
  std::ofstream(dir / "nan.obj") << "v nan nan nan\nv nan nan nan\nv nan nan nan\nf 1 2 3\n";
  // ASCII STL that assimp read as far as it could: half a file, four vertices, no endloop, an
  // exponent that overflows.
  const std::string facet = "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
  const std::string two = "solid s\n" + facet + facet + "endsolid s\n";
  std::ofstream(dir / "half.stl") << two.substr(0, two.size() / 2);
  std::ofstream(dir / "four.stl") << "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                     "vertex 1 1 0\nendloop\nendfacet\nendsolid s\n";
  std::ofstream(dir / "noendloop.stl") << "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                          "vertex 0 1 0\nendfacet\nendsolid s\n";
  std::ofstream(dir / "exponent.stl") << "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                                         "vertex 1e99999999999999999999 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid s\n";
  std::ofstream(dir / "good_ascii.stl") << two;
  std::ofstream(dir / "flat.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
  std::ofstream(dir / "far.obj") << "v 0 0 0\nv 10 0 0\nv 0 1 0\nf 1 2 3\n";
  {
    std::mt19937_64 rng(3);
    std::ofstream random(dir / "random.obj", std::ios::binary);
    for (int i = 0; i < 3000; ++i) random.put(static_cast<char>(rng() & 0xFF));
  }
  const std::pair<std::string, std::string> cases[] = {
      {"nan_binary.stl", "not finite"}, {"inf_binary.stl", "not finite"}, {"nan_ascii.stl", ""},
      {"nan.obj", ""},                  {"flat.obj", "non-zero area"},    {"random.obj", ""},
      {"half.stl", "ASCII STL: expected"}, {"four.stl", "expected 'endloop', found 'vertex'"},
      {"noendloop.stl", "expected 'endloop', found 'endfacet'"}, {"exponent.stl", "not a finite number"},
  };
  for (const auto& [file, reason] : cases) {
    const std::string msg = pkg.load_error(mesh_link("arm", "package://test-meshes/meshes/" + file));
    EXPECT_NE(msg.find("link 'arm', collision element 1"), std::string::npos) << file << ": " << msg;
    EXPECT_NE(msg.find(file), std::string::npos) << msg;
    EXPECT_NE(msg.find(reason), std::string::npos) << file << ": " << msg;
  }
  EXPECT_EQ(pkg.load(mesh_link("arm", "package://test-meshes/meshes/good_ascii.stl")).links()[0].collision[0].mesh->triangles.size(), 2u);
  // Scaled beyond any robot: refused, not answered "free at distance 0".
  const std::string msg = pkg.load_error(mesh_link("arm", "package://test-meshes/meshes/far.obj", "1e5 1 1"));
  EXPECT_NE(msg.find("beyond"), std::string::npos) << msg;
}

// Hostile Collada: assimp crashed (a stride of 10^6), allocated without end (a non-integer in
// <p>: 19 GB seen) or accepted nonsense (indices of -1 or 2^32 - 1, counts beyond the array,
// strides of 0 or -3, an offset of -1). Each is now an error naming the file; the importer runs
// in a child process bounded in memory and time.
TEST(RobotModel, HostileColladaIsAnErrorNotACrashOrARunaway) {
  const ScratchPackage pkg;
  const fs::path dir = pkg.root / "test-meshes" / "meshes";
  const std::pair<std::string, std::string> cases[] = {
      {"stride=\"3\"", "stride=\"1000000\""}, {"stride=\"3\"", "stride=\"0\""},
      {"stride=\"3\"", "stride=\"-3\""},      {"<p>0 1 2</p>", "<p>0 1 -1</p>"},
      {"<p>0 1 2</p>", "<p>0 1 2147483648</p>"}, {"<p>0 1 2</p>", "<p>0 1 4294967295</p>"},
      {"count=\"3\" stride", "count=\"30\" stride"}, {"offset=\"0\"", "offset=\"-1\""},
      // A node that instances itself: endless recursion in assimp (found by the fuzz corpus).
      {"<instance_geometry url=\"#tri\"/>", "<instance_geometry url=\"#tri\"/><instance_node url=\"#child\"/>"},
  };
  int i = 0;
  for (const auto& [from, to] : cases) {
    const std::string file = "hostile" + std::to_string(i++) + ".dae";
    write_collada(dir / file, from, to);
    const std::string msg = pkg.load_error(mesh_link("arm", "package://test-meshes/meshes/" + file));
    EXPECT_NE(msg.find("link 'arm', collision element 1"), std::string::npos) << to << ": " << msg;
    EXPECT_NE(msg.find(file), std::string::npos) << to << ": " << msg;
    EXPECT_EQ(msg.find("crashed the importer"), std::string::npos) << "refused before assimp ran: " << msg;
  }
  // The runaway allocation, stopped at a small bound here (the default is 1 GiB).
  write_collada(dir / "runaway.dae", "<p>0 1 2</p>", "<p>0 x 2</p>");
  const auto start = std::chrono::steady_clock::now();
  try {
    load_mesh((dir / "runaway.dae").string(), Vec3::Ones(), MeshImportLimits{std::size_t(192) << 20, 60.0});
    ADD_FAILURE() << "a Collada <p> list with a non-integer loaded";
  } catch (const MeshLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("runaway.dae"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(60));
  // The memory bound itself: a valid mesh of 200,000 triangles needs far more than 8 MiB.
  {
    std::ofstream big(dir / "big.obj");
    for (int i = 0; i < 100000; ++i) big << "v " << i << " 0 0\nv " << i << " 1 0\nv " << i << " 0 1\n";
    for (int i = 0; i < 100000; ++i) big << "f " << 3 * i + 1 << " " << 3 * i + 2 << " " << 3 * i + 3 << "\n";
    for (int i = 0; i < 100000; ++i) big << "f " << 3 * i + 1 << " " << 3 * i + 3 << " " << 3 * i + 2 << "\n";
  }
  try {
    load_mesh((dir / "big.obj").string(), Vec3::Ones(), MeshImportLimits{std::size_t(8) << 20, 60.0});
    ADD_FAILURE() << "no memory bound";
  } catch (const MeshLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("could not be loaded within 8 MiB"), std::string::npos) << e.what();
  }
  EXPECT_EQ(load_mesh((dir / "big.obj").string()).triangles.size(), 200000u) << "within the default bound";
  // A hang: a time bound of 0 s stops even a good file, with the reason.
  try {
    load_mesh((dir / "box.stl").string(), Vec3::Ones(), MeshImportLimits{std::size_t(1) << 30, 0.0});
    ADD_FAILURE() << "no time bound";
  } catch (const MeshLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("could not be loaded within 0 s"), std::string::npos) << e.what();
  }
}

TEST(RobotModel, MimicAndFreeJoints) {
  const RobotModel m = [] {
    const std::string xml = std::string("<robot name=\"m\"><link name=\"base\"/><link name=\"a\"/><link name=\"b\"/><link name=\"f\"/>") +
        "<joint name=\"ja\" type=\"prismatic\"><parent link=\"base\"/><child link=\"a\"/><axis xyz=\"1 0 0\"/>"
        "<limit lower=\"0\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>"
        "<joint name=\"jb\" type=\"prismatic\"><parent link=\"base\"/><child link=\"b\"/><axis xyz=\"0 1 0\"/>"
        "<limit lower=\"0\" upper=\"1\" effort=\"1\" velocity=\"1\"/><mimic joint=\"ja\" multiplier=\"-2\" offset=\"0.5\"/></joint>"
        "<joint name=\"jf\" type=\"floating\"><parent link=\"base\"/><child link=\"f\"/></joint></robot>";
    return RobotModel::from_urdf(*parse_robot_description(xml), PackageResolver({}));
  }();
  ASSERT_EQ(m.variable_names(), std::vector<std::string>{"ja"});
  const double q = 0.25;
  std::vector<Transform> poses;
  std::vector<Transform> free(m.joints().size());
  free[m.joint_index("jf")] = Transform::Translation(Vec3(1, 2, 3));
  forward_kinematics(m, &q, poses, &free);
  EXPECT_NEAR(poses[m.link_index("a")].t.x(), 0.25, 1e-15);
  EXPECT_NEAR(poses[m.link_index("b")].t.y(), -2 * 0.25 + 0.5, 1e-15);
  EXPECT_EQ(poses[m.link_index("f")].t, Vec3(1, 2, 3));
  forward_kinematics(m, &q, poses);  // no free poses: identity
  EXPECT_EQ(poses[m.link_index("f")].t, Vec3::Zero());
  // The plan: the same, for a chosen link.
  std::vector<bool> wanted(m.links().size(), false);
  wanted[m.link_index("b")] = wanted[m.link_index("f")] = true;
  const KinematicsPlan plan(m, wanted);
  EXPECT_EQ(plan.steps(), 2u);
  plan.compute(&q, poses, &free);
  EXPECT_NEAR(poses[m.link_index("b")].t.y(), -2 * 0.25 + 0.5, 1e-15);
  EXPECT_EQ(poses[m.link_index("f")].t, Vec3(1, 2, 3));
}

// The plan's pose products (two rows in SSE2 lanes, a revolute step's two turned columns mixed as
// they are computed) equal, bit for bit, the scalar product parent * fixed with its sums in row
// order, then the rotation's mix of two columns: what the batch kernel computes in its lanes and
// what the planner's replayed answers were compared against. Each step from the plan's own parent
// pose, on every robot, every joint kind the robots have.
Transform scalar_product(const Transform& a, const Transform& b) {
  Transform o;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) o.R(r, c) = a.R(r, 0) * b.R(0, c) + a.R(r, 1) * b.R(1, c) + a.R(r, 2) * b.R(2, c);
    o.t[r] = a.R(r, 0) * b.t[0] + a.R(r, 1) * b.t[1] + a.R(r, 2) * b.t[2] + a.t[r];
  }
  return o;
}

TEST(KinematicsPlan, StepsEqualTheScalarProductsBitForBit) {
  BVH_REQUIRE_ROBOTS();
  std::mt19937_64 rng(7);
  int revolute = 0;
  for (const char* robot : {"panda", "ur5e", "pr2", "abb_irb2400"}) {
    SCOPED_TRACE(robot);
    const RobotModel model = RobotModel::from_urdf(*load_robot_description_file(test::robots_dir() + "/" + robot + "/robot.urdf"),
                                                   PackageResolver({test::robots_dir() + "/" + robot}));
    const KinematicsPlan plan(model, std::vector<bool>(model.links().size(), true));
    std::vector<Transform> poses;
    for (int sample = 0; sample < 50; ++sample) {
      const std::vector<double> state = random_configuration(model, rng);
      plan.compute(state.data(), poses);
      for (const KinematicsPlan::Step& step : plan.step_list()) {
        const bool turns = step.type == JointType::kRevolute || step.type == JointType::kContinuous;
        if (!(step.type == JointType::kFixed || (turns && step.axis >= 0))) continue;
        Transform want = scalar_product(poses[step.parent], step.fixed);
        if (turns && step.variable >= 0) {
          double sine, cosine;
          sin_cos(step.multiplier * state[step.variable] + step.offset, sine, cosine);
          sine *= step.axis_vector[step.axis];
          const int i = (step.axis + 1) % 3, j = (step.axis + 2) % 3;
          for (int r = 0; r < 3; ++r) {
            const double a = want.R(r, i), b = want.R(r, j);
            want.R(r, i) = cosine * a + sine * b;
            want.R(r, j) = cosine * b - sine * a;
          }
          ++revolute;
        }
        const Transform& got = poses[step.link];
        for (int e = 0; e < 12; ++e) {
          const double w = e < 9 ? want.R(e / 3, e % 3) : want.t[e - 9], g = e < 9 ? got.R(e / 3, e % 3) : got.t[e - 9];
          ASSERT_EQ(w, g) << model.links()[step.link].name << " element " << e;
        }
      }
    }
  }
  EXPECT_GT(revolute, 1000);
}

// A motion that moves a few joints poses only the links below them (SceneChecker's intervals):
// from the poses of one state, the steps below the joints that changed give the other state's
// poses bit for bit, and the links no changed joint is above keep theirs. pr2 with one arm moved
// recomputes a fraction of its steps.
TEST(KinematicsPlan, ComputeStepsPosesTheLinksBelowTheMovedJointsBitForBit) {
  BVH_REQUIRE_ROBOTS();
  std::mt19937_64 rng(11);
  for (const char* robot : {"panda", "pr2"}) {
    SCOPED_TRACE(robot);
    const RobotModel model = RobotModel::from_urdf(*load_robot_description_file(test::robots_dir() + "/" + robot + "/robot.urdf"),
                                                   PackageResolver({test::robots_dir() + "/" + robot}));
    const KinematicsPlan plan(model, std::vector<bool>(model.links().size(), true));
    std::size_t partial_steps = 0, all_steps = 0;
    for (int sample = 0; sample < 40; ++sample) {
      const std::vector<double> a = random_configuration(model, rng);
      std::vector<double> b = random_configuration(model, rng);
      // Some variables changed, the others as in a.
      const std::size_t keep = std::uniform_int_distribution<std::size_t>(0, b.size())(rng);
      for (std::size_t v = 0; v < keep; ++v) b[(v * 7 + static_cast<std::size_t>(sample)) % b.size()] = a[(v * 7 + static_cast<std::size_t>(sample)) % b.size()];
      std::vector<Transform> from_a, want;
      plan.compute(a.data(), from_a);
      plan.compute(b.data(), want);
      std::vector<char> moves(model.links().size(), 0);
      std::vector<std::uint32_t> steps;
      for (std::size_t i = 0; i < plan.step_list().size(); ++i) {
        const KinematicsPlan::Step& step = plan.step_list()[i];
        moves[step.link] = moves[step.parent] || (step.variable >= 0 && a[step.variable] != b[step.variable]);
        if (moves[step.link]) steps.push_back(static_cast<std::uint32_t>(i));
      }
      partial_steps += steps.size();
      all_steps += plan.step_list().size();
      std::vector<Transform> got = from_a;
      plan.compute_steps(b.data(), got, steps.data(), steps.size());
      for (const KinematicsPlan::Step& step : plan.step_list()) {
        for (int e = 0; e < 12; ++e) {
          const Transform& w = want[step.link];
          const Transform& g = got[step.link];
          ASSERT_EQ(e < 9 ? w.R(e / 3, e % 3) : w.t[e - 9], e < 9 ? g.R(e / 3, e % 3) : g.t[e - 9])
              << model.links()[step.link].name << " element " << e << (moves[step.link] ? " (moved)" : " (kept)");
        }
      }
    }
    EXPECT_LT(partial_steps, all_steps);
  }
}

}  // namespace
}  // namespace bvh_collision
