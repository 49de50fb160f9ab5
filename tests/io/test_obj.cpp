#include "io/obj.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "core/error.h"

namespace hf {
namespace {

namespace fs = std::filesystem;

std::string obj_temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("hf_test_obj_" + std::to_string(::getpid()) + "_" + name)).string();
}

TriangleMesh obj_make_mesh(bool normals, bool colors, int n = 30) {
  TriangleMesh m;
  for (int i = 0; i < n; ++i) {
    const float t = static_cast<float>(i);
    m.vertices.emplace_back(t / 3.0f, -t * 1e-7f, 1e20f / (t + 1.0f));
    if (normals) m.normals.emplace_back(Eigen::Vector3f(1.0f / 3.0f, t / 7.0f, -0.3f).normalized());
    if (colors) m.colors.push_back(Rgb8{std::uint8_t(i * 37), std::uint8_t(255 - i), std::uint8_t(i * 101 + 3)});
  }
  for (int i = 0; i + 2 < n; ++i) m.triangles.emplace_back(i, (i * 7 + 1) % n, n - 1 - i);
  return m;
}

bool obj_same_bits(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (std::bit_cast<std::uint32_t>(a[i][k]) != std::bit_cast<std::uint32_t>(b[i][k])) return false;
  return true;
}

class ObjRoundTrip : public ::testing::TestWithParam<std::tuple<bool, bool>> {};

TEST_P(ObjRoundTrip, IsBitExact) {
  const auto [normals, colors] = GetParam();
  const TriangleMesh m = obj_make_mesh(normals, colors);
  const std::string path = obj_temp_path("rt.obj");
  write_obj(path, m);
  const TriangleMesh back = read_obj(path);
  EXPECT_TRUE(obj_same_bits(m.vertices, back.vertices));
  EXPECT_TRUE(obj_same_bits(m.normals, back.normals));
  EXPECT_EQ(m.colors, back.colors);
  EXPECT_EQ(m.triangles, back.triangles);
  fs::remove(path);
}

INSTANTIATE_TEST_SUITE_P(AllCombinations, ObjRoundTrip, ::testing::Combine(::testing::Bool(), ::testing::Bool()));

TEST(ObjWrite, Layout) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 51}};
  m.triangles = {{0, 1, 2}};
  EXPECT_EQ(format_obj(m, {"a\nb"}),
            "# a\n# b\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.2\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n");
}

TEST(ObjWrite, InvalidMeshIsRefused) {
  TriangleMesh m = obj_make_mesh(false, false, 4);
  m.triangles.emplace_back(0, -1, 2);
  const std::string path = obj_temp_path("bad.obj");
  EXPECT_THROW(write_obj(path, m), Error);
  EXPECT_FALSE(fs::exists(path));
}

TEST(ObjRead, CornerFormsNegativeIndicesPolygonsAndIgnoredStatements) {
  const std::string text =
      "# comment\nmtllib x.mtl\no thing\ng group\n"
      "v 0 0 0\nv 1 0 0 1.0\nv 1 1 0   # trailing comment\r\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvn 0 0 1\nvn 0 0 -1\n"
      "usemtl red\ns off\n"
      "f 1/1/1 2/2/1 3/2/1 4/1/1\n"   // quad -> (0 1 2) (0 2 3), all corners normal 1
      "f -4//-1 -2//-1 -1//-2\n"      // relative: vertices 0 2 3; vertex 3 gets normals 2 and 1 -> mixed
      "f 1/1 2/2 3\n"
      "l 1 2\np 3\n";
  const TriangleMesh m = parse_obj(text, "t.obj");
  ASSERT_EQ(m.vertices.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(m.triangles[2], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(m.triangles[3], Eigen::Vector3i(0, 1, 2));
  ASSERT_EQ(m.normals.size(), 4u);
  EXPECT_EQ(m.normals[1], Eigen::Vector3f(0, 0, 1));
  // Vertex 0's corners name normal 1 twice (the fanned quad) and normal 2 once: the normalised mean is +z.
  EXPECT_EQ(m.normals[0], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(m.normals[3], Eigen::Vector3f(0, 0, 1));  // both corners name normal 1
  EXPECT_TRUE(m.colors.empty());
}

TEST(ObjRead, OppositeCornerNormalsLeaveAZeroNormal) {
  const TriangleMesh m = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 -1\nf 1//1 2//1 3//1\nf 1//2 3//2 2//2\n", "o.obj");
  ASSERT_EQ(m.normals.size(), 3u);
  EXPECT_EQ(m.normals[0], Eigen::Vector3f(0, 0, 0));
}

TEST(ObjRead, NormalsByIndexWhenFacesNameNone) {
  const TriangleMesh m = parse_obj("v 0 0 0\nv 1 0 0\nvn 0 1 0\nvn 1 0 0\n", "p.obj");
  ASSERT_EQ(m.normals.size(), 2u);
  EXPECT_EQ(m.normals[1], Eigen::Vector3f(1, 0, 0));
}

TEST(ObjRead, ForwardReferencesAreCheckedAtTheEnd) {
  const TriangleMesh m = parse_obj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "fwd.obj");
  EXPECT_EQ(m.triangles.size(), 1u);
}

struct ObjBadCase {
  std::string text, expected;
};

TEST(ObjRead, MalformedInputGivesOneClearParseError) {
  const std::vector<ObjBadCase> cases = {
      {"v 0 0\n", "bad.obj:1: expected 'v x y z [w]' or 'v x y z r g b', got 2 numbers"},
      {"v 0 0 0\nv 0 zero 0\n", "bad.obj:2: expected a number for y, got 'zero'"},
      {"v 0 0 nan\n", "bad.obj:1: expected a finite float for z, got 'nan'"},
      {"v 0 0 1e39\n", "bad.obj:1: expected a finite float for z, got '1e39'"},
      {"vn 0 1\n", "bad.obj:1: expected 'vn x y z', got 2 numbers"},
      {"v 0 0 0\nv 1 0 0\nf 1 2\n", "bad.obj:3: expected a face with at least 3 corners, got 2"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "bad.obj:4: expected a non-zero vertex index (OBJ indices start at 1), got 0"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "bad.obj:4: expected a relative vertex index within the 3 defined so far, got -4"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "bad.obj:4: expected an integer vertex index, got 'x'"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n\n", "bad.obj:4: expected vertex indices in [1, 3], got 4"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n", "bad.obj:5: expected normal indices in [1, 1], got 2"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", "bad.obj:4: expected a corner 'v', 'v/t', 'v//n' or 'v/t/n', got '1/1/1/1'"},
      {"v 0 0 0 1 0 0\nv 1 0 0\n", "bad.obj:2: expected colours 'v x y z r g b' as on the first vertex (line 1)"},
      {"v 0 0 0\nv 1 0 0 1 0 0\n", "bad.obj:2: expected no colours as on the first vertex (line 1)"},
  };
  for (const ObjBadCase& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      parse_obj(c.text, "bad.obj");
      ADD_FAILURE() << "expected hf::ParseError";
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos)
          << "  message: " << e.what() << "\n  expected to contain: " << c.expected;
    }
  }
  EXPECT_THROW(read_obj(obj_temp_path("missing.obj")), Error);
}

// Real head meshes (PROVENANCE.md gives the counts and that Max Planck and Nefertiti are closed manifolds).
struct HeadMesh {
  const char* file;
  size_t vertices, triangles;
  bool closed;
};

TEST(ObjRead, RealHeadMeshes) {
  const std::string dir = std::string(HF_SHARED_DIR) + "/data/head_meshes/";
  if (!fs::exists(dir)) GTEST_SKIP() << "real data not present: " << dir;
  for (const HeadMesh& h : {HeadMesh{"libigl_face_head.obj", 25905, 51712, false},
                            HeadMesh{"max_planck_decimated.obj", 5272, 10540, true},
                            HeadMesh{"nefertiti.obj", 49971, 99938, true}}) {
    SCOPED_TRACE(h.file);
    const TriangleMesh m = read_obj(dir + h.file);
    EXPECT_EQ(m.vertices.size(), h.vertices);
    EXPECT_EQ(m.triangles.size(), h.triangles);
    m.validate();
    // Every undirected edge of a closed, consistently oriented mesh is used once in each direction.
    std::vector<std::uint64_t> edges;
    for (const auto& t : m.triangles)
      for (int k = 0; k < 3; ++k)
        edges.push_back((static_cast<std::uint64_t>(t[k]) << 32) | static_cast<std::uint32_t>(t[(k + 1) % 3]));
    std::sort(edges.begin(), edges.end());
    size_t unmatched = 0;
    for (size_t i = 0; i < edges.size(); ++i)
      if ((i > 0 && edges[i] == edges[i - 1]) ||
          !std::binary_search(edges.begin(), edges.end(), (edges[i] << 32) | (edges[i] >> 32)))
        ++unmatched;
    std::cout << h.file << ": " << m.vertices.size() << " vertices, " << m.triangles.size() << " triangles, "
              << unmatched << " boundary or inconsistent directed edges\n";
    if (h.closed) EXPECT_EQ(unmatched, 0u);
    else EXPECT_LT(unmatched, 200u);  // the libigl head is open at the neck (96 boundary edges)
  }
}

}  // namespace
}  // namespace hf
