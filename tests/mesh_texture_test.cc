// The mesh made ready for other tools, on a sphere whose surface and colour are known: simplified to a triangle
// budget it stays closed and on the sphere; textured, no two charts share a texel (only neighbouring triangles of
// one chart do, along their edge) and the texture seen through the texture coordinates gives the colour the field
// gives there.

#include <catch2/catch.hpp>

#include <cmath>
#include <map>

#include "base/errors.h"
#include "mesh/mesh.h"
#include "mesh/mesh_simplify.h"
#include "mesh/texture_atlas.h"
#include "tests/sphere_field.h"

namespace p2n::testing {
namespace {

Mesh MarchedSphere(int resolution) {
  MeshOptions options;
  options.resolution = resolution;
  options.density_threshold = kThreshold;
  return ExtractMesh(SphereModel(), options);
}

// The texture read bilinearly at (u, v), texel centres at half-integers (as a GPU samples it without mipmaps).
Eigen::Vector3f Sample(const TexturedMesh& mesh, const Eigen::Vector2f& uv) {
  const int n = mesh.texture_size;
  const float x = uv.x() * n - 0.5f, y = uv.y() * n - 0.5f;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float fx = x - x0, fy = y - y0;
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (int dy = 0; dy < 2; ++dy) {
    for (int dx = 0; dx < 2; ++dx) {
      const int px = std::clamp(x0 + dx, 0, n - 1), py = std::clamp(y0 + dy, 0, n - 1);
      const float weight = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy);
      for (int c = 0; c < 3; ++c) sum[c] += weight * mesh.texture[3 * (size_t(py) * n + px) + c];
    }
  }
  return sum;
}

}  // namespace

TEST_CASE("simplified mesh: within the budget, still closed, on the sphere, its normals and colours carried",
          "[mesh]") {
  const Mesh marched = MarchedSphere(96);
  REQUIRE(marched.triangles.size() > 20000);
  const SimplifiedMesh simplified = SimplifyMesh(marched, 2000);
  const Mesh& mesh = simplified.mesh;
  CHECK(mesh.triangles.size() <= 2000);
  CHECK(mesh.triangles.size() > 1500);
  CHECK_FALSE(simplified.sloppy);
  CHECK(CountEdges(mesh).watertight());
  REQUIRE(mesh.normals.size() == mesh.positions.size());
  REQUIRE(mesh.colours.size() == mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    CHECK(std::abs(mesh.positions[v].norm() - kRadius) < 0.01f);  // the marched sphere's own vertices
    CHECK(mesh.normals[v].dot(mesh.positions[v].normalized()) > 0.99f);
    CHECK(std::abs(mesh.colours[v][0] - 127.5f * (1 + mesh.normals[v][0])) <= 2.0f);
  }
  // The chords of 2,000 triangles round a sphere: within a few percent of its volume, as reported.
  const double volume = SignedVolume(mesh.positions, mesh.triangles);
  CHECK(volume == Approx(4.0 / 3.0 * M_PI * std::pow(kRadius, 3)).epsilon(0.03));
  CHECK((simplified.error > 0 && simplified.error < 0.05 * kRadius));
  CHECK(SimplifyMesh(mesh, 5000).mesh.triangles.size() == mesh.triangles.size());  // under the budget: as it is
}

TEST_CASE("texture: charts apart, each texel the colour of its surface point, seen through the coordinates", "[mesh]") {
  const NerfModel model = SphereModel();
  const Mesh mesh = SimplifyMesh(MarchedSphere(64), 3000).mesh;
  const TexturedMesh textured = BakeTexture(
      mesh, 512, [&](const auto& points, const auto& normals) { return SurfaceColours(model, points, normals); });
  REQUIRE(textured.triangles.size() == mesh.triangles.size());
  REQUIRE(textured.uvs.size() == textured.positions.size());
  CHECK(SignedVolume(textured.positions, textured.triangles) == Approx(SignedVolume(mesh.positions, mesh.triangles)));

  // Texel centres inside each triangle's texture coordinates: one triangle's, or those on the edge two neighbours
  // of a chart share (two corners' positions in common).
  const int n = textured.texture_size;
  std::map<size_t, size_t> owner;
  size_t shared = 0;
  for (size_t t = 0; t < textured.triangles.size(); ++t) {
    const auto& corners = textured.triangles[t];
    Eigen::Vector2f uv[3];
    for (int c = 0; c < 3; ++c) {
      uv[c] = textured.uvs[corners[c]] * n;
      REQUIRE((uv[c].minCoeff() > 0 && uv[c].maxCoeff() < n));
    }
    const auto edge = [](const Eigen::Vector2f& a, const Eigen::Vector2f& b, const Eigen::Vector2f& p) {
      return (b - a).x() * (p - a).y() - (b - a).y() * (p - a).x();
    };
    const float area = edge(uv[0], uv[1], uv[2]);
    REQUIRE(area != 0);
    const Eigen::Vector2f low = uv[0].cwiseMin(uv[1]).cwiseMin(uv[2]), high = uv[0].cwiseMax(uv[1]).cwiseMax(uv[2]);
    for (int y = int(low.y()); y <= int(high.y()); ++y) {
      for (int x = int(low.x()); x <= int(high.x()); ++x) {
        const Eigen::Vector2f p(x + 0.5f, y + 0.5f);
        bool inside = true;
        for (int e = 0; e < 3; ++e) inside &= edge(uv[e], uv[(e + 1) % 3], p) * area >= -1e-3f * std::abs(area);
        if (!inside) continue;
        const auto [it, first] = owner.emplace(size_t(y) * n + x, t);
        if (first) continue;
        int common = 0;
        for (const uint32_t a : textured.triangles[it->second]) {
          for (const uint32_t b : corners) common += textured.positions[a] == textured.positions[b];
        }
        CHECK(common == 2);
        ++shared;
      }
    }
  }
  CHECK(owner.size() > 10 * textured.triangles.size());
  CHECK(shared < owner.size() / 4);

  // Seen along -normal the sphere's colour is (1 + normal) / 2; at each triangle's centroid, through its texture
  // coordinates, the colour of the normal interpolated there.
  for (const auto& t : textured.triangles) {
    const Eigen::Vector2f uv = (textured.uvs[t[0]] + textured.uvs[t[1]] + textured.uvs[t[2]]) / 3;
    const Eigen::Vector3f normal =
        (textured.normals[t[0]] + textured.normals[t[1]] + textured.normals[t[2]]).normalized();
    const Eigen::Vector3f expected = 127.5f * (Eigen::Vector3f::Ones() + normal);
    CHECK((Sample(textured, uv) - expected).cwiseAbs().maxCoeff() <= 3.0f);
  }
}

TEST_CASE("texture: more charts than the texture holds at any chart size is an error that says what to change",
          "[mesh]") {
  const Mesh mesh = SimplifyMesh(MarchedSphere(48), 3000).mesh;
  CHECK_THROWS_AS(
      BakeTexture(mesh, 8,
                  [](const auto& points, const auto&) { return std::vector<std::array<uint8_t, 3>>(points.size()); }),
      UserError);
  CHECK_THROWS_WITH(
      BakeTexture(mesh, 8,
                  [](const auto& points, const auto&) { return std::vector<std::array<uint8_t, 3>>(points.size()); }),
      Catch::Contains("export.texture_size") && Catch::Contains("export.max_triangles"));
}

}  // namespace p2n::testing
