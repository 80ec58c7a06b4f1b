// SPDX-License-Identifier: MIT
// Tests for puppeteer/src/snapshot.h: coverage, shading, depth order, framing and the PNG file.
#include "snapshot.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>

#include <glm/geometric.hpp>

#include "failure_text.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

// Icosphere of radius `radius` around `centre`: vertices on the sphere, outward unit normals, one colour.
Mesh icosphere(int subdivisions, float radius, glm::vec3 centre, glm::vec3 rgb) {
  const float g = (1.0f + std::sqrt(5.0f)) / 2.0f;
  std::vector<glm::vec3> points = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                   {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (glm::vec3& p : points) p = glm::normalize(p);
  std::vector<uint32_t> triangles = {0, 11, 5, 0, 5,  1,  0,  1,  7,  0,  7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                                     4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9,  4,  3,  4,  2,  3, 2, 6, 3, 6,
                                     8, 3,  8,  9, 4,  9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto found = midpoints.find(key);
      if (found != midpoints.end()) return found->second;
      points.push_back(glm::normalize(points[a] + points[b]));
      const auto index = static_cast<uint32_t>(points.size() - 1);
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<uint32_t> finer;
    for (size_t t = 0; t < triangles.size(); t += 3) {
      const uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    triangles = std::move(finer);
  }
  Mesh mesh;
  for (const glm::vec3& p : points) {
    const glm::vec3 q = centre + radius * p;
    mesh.positions.insert(mesh.positions.end(), {q.x, q.y, q.z});
    mesh.normals.insert(mesh.normals.end(), {p.x, p.y, p.z});
    mesh.colors.insert(mesh.colors.end(), {rgb.r, rgb.g, rgb.b});
  }
  mesh.indices = std::move(triangles);
  return mesh;
}

const glm::vec3 kRed{0.8f, 0.2f, 0.05f};

struct Image {
  int width, height;
  std::vector<uint8_t> pixels;
  const uint8_t* at(int x, int y) const { return &pixels[(static_cast<size_t>(y) * width + x) * 4]; }
  bool same(int x, int y, const Image& other) const { return std::equal(at(x, y), at(x, y) + 4, other.at(x, y)); }
};

Image render(const Mesh& mesh, const SnapshotOptions& options) {
  return {options.width, options.height, renderMesh(mesh, options)};
}

SnapshotOptions frontView(int size) {
  SnapshotOptions options;
  options.width = options.height = size;
  options.camera = Camera{.eye = {0, 0, 4}, .target = {0, 0, 0}, .up = {0, 1, 0}, .verticalFov = 0.6f};
  return options;
}

uint8_t srgbByte(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  const float e = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(e * 255.0f + 0.5f);
}

TEST(Snapshot, SphereCoversItsProjectedDisk) {
  const SnapshotOptions options = frontView(200);
  const Image background = render(Mesh{}, options);
  const Image image = render(icosphere(4, 1.0f, glm::vec3(0.0f), kRed), options);
  ASSERT_EQ(image.pixels.size(), 200u * 200u * 4u);
  int covered = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) covered += image.same(x, y, background) ? 0 : 1;
  }
  // A sphere of radius r seen from distance d subtends asin(r / d); at the image centre its outline is a circle.
  const double radiusPixels = 100.0 * std::tan(std::asin(1.0 / 4.0)) / std::tan(0.3);
  const double expected = std::numbers::pi * radiusPixels * radiusPixels;
  // Pixels the outline only partly covers differ from the background too: allow one pixel around the rim.
  EXPECT_GT(covered, expected * 0.98);
  EXPECT_LT(covered, expected * 1.01 + 2.0 * std::numbers::pi * radiusPixels);
}

TEST(Snapshot, CentrePixelIsTheLitMeshColour) {
  const SnapshotOptions options = frontView(101);
  const Image image = render(icosphere(3, 1.0f, glm::vec3(0.0f), kRed), options);
  const uint8_t* centre = image.at(50, 50);
  // Lit: brighter than ambient alone, no brighter than the full albedo; hue kept (red > green > blue).
  EXPECT_GT(centre[0], srgbByte(kRed.r * options.ambient) + 20);
  EXPECT_LE(centre[0], srgbByte(kRed.r) + 1);
  EXPECT_GT(centre[1], srgbByte(kRed.g * options.ambient));
  EXPECT_LE(centre[1], srgbByte(kRed.g) + 1);
  EXPECT_GT(centre[0], centre[1] + 60);
  EXPECT_GT(centre[1], centre[2]);
  EXPECT_EQ(centre[3], 255);
  // The upper left (towards the light) is brighter than the lower right.
  EXPECT_GT(image.at(38, 38)[0], image.at(62, 62)[0] + 10);
}

TEST(Snapshot, CornersAreTheBackgroundGradient) {
  const SnapshotOptions options = frontView(64);
  const Image image = render(icosphere(2, 1.0f, glm::vec3(0.0f), kRed), options);
  for (const auto& [x, y] : {std::pair{0, 0}, {63, 0}, {0, 63}, {63, 63}}) {
    const uint8_t* p = image.at(x, y);
    // Light grey: nearly equal channels, bluish by at most a little, bright.
    EXPECT_LE(std::abs(p[0] - p[1]), 1) << x << "," << y;
    EXPECT_GE(p[2], p[0]) << x << "," << y;
    EXPECT_GT(p[0], 170) << x << "," << y;
  }
  EXPECT_GT(image.at(0, 0)[0], image.at(0, 63)[0] + 15);  // lighter at the top
  EXPECT_NEAR(image.at(0, 0)[0], srgbByte(options.backgroundTop.r), 2);
  EXPECT_NEAR(image.at(0, 63)[0], srgbByte(options.backgroundBottom.r), 2);
}

TEST(Snapshot, NearerSurfaceWinsWhateverTheDrawingOrder) {
  // Seen from z = 4 in an 80-pixel image, the red sphere's outline has a radius of about 13 pixels, the green
  // one's about 40.
  const Mesh nearRed = icosphere(2, 0.3f, {0, 0, 1}, kRed);
  const Mesh farGreen = icosphere(2, 1.5f, {0, 0, -1}, {0.1f, 0.8f, 0.1f});
  for (const bool redFirst : {true, false}) {
    Mesh both = redFirst ? nearRed : farGreen;
    appendMesh(both, redFirst ? farGreen : nearRed);
    const Image image = render(both, frontView(80));
    const uint8_t* centre = image.at(40, 40);
    EXPECT_GT(centre[0], centre[1] + 50) << "red first: " << redFirst;
    const uint8_t* beside = image.at(40, 20);  // outside the small red sphere, inside the green one
    EXPECT_GT(beside[1], beside[0] + 50) << "red first: " << redFirst;
  }
}

TEST(Snapshot, VertexColoursAreInterpolated) {
  // A camera-facing quad, red on the left edge and blue on the right.
  Mesh quad;
  quad.positions = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  quad.colors = {1, 0, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0};
  quad.indices = {0, 1, 2, 0, 2, 3};
  const Image image = render(quad, frontView(100));
  // The quad spans pixels 10..90 horizontally.
  const uint8_t* left = image.at(20, 50);
  const uint8_t* middle = image.at(50, 50);
  const uint8_t* right = image.at(80, 50);
  EXPECT_GT(left[0], left[2] + 30);
  EXPECT_GT(right[2], right[0] + 30);
  EXPECT_LE(std::abs(middle[0] - middle[2]), 12);
  EXPECT_GT(middle[0], 40);
}

TEST(Snapshot, BackFacesAreLitLikeFrontFaces) {
  const Mesh sphere = icosphere(3, 1.0f, glm::vec3(0.0f), kRed);
  Mesh insideOut = sphere;
  for (size_t t = 0; t < insideOut.triangleCount(); ++t)
    std::swap(insideOut.indices[3 * t + 1], insideOut.indices[3 * t + 2]);
  for (float& n : insideOut.normals) n = -n;
  // Winding that disagrees with the vertex normals: the normals say which side is out.
  Mesh rewound = sphere;
  for (size_t t = 0; t < rewound.triangleCount(); ++t)
    std::swap(rewound.indices[3 * t + 1], rewound.indices[3 * t + 2]);
  const Image front = render(sphere, frontView(64)), back = render(insideOut, frontView(64));
  const Image reversed = render(rewound, frontView(64));
  for (const auto& [x, y] : {std::pair{32, 32}, {24, 24}, {40, 44}}) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(front.at(x, y)[k], back.at(x, y)[k], 2) << x << "," << y;
      EXPECT_NEAR(front.at(x, y)[k], reversed.at(x, y)[k], 2) << x << "," << y;
    }
  }
}

TEST(Snapshot, FramedMeshFillsTheViewWithoutTouchingTheBorder) {
  Mesh mesh = icosphere(2, 1.0f, {10, 0, 0}, kRed);
  appendMesh(mesh, icosphere(2, 1.0f, {13, 2, -1}, kRed));  // an off-centre, elongated subject
  for (const glm::vec3 direction : {kFrontThreeQuarter, glm::vec3(0, 0, 1), glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0)}) {
    SnapshotOptions options;
    options.width = 160;
    options.height = 120;
    options.camera = frameMesh(mesh, direction, 160.0f / 120.0f);
    const Image background = render(Mesh{}, options);
    const Image image = render(mesh, options);
    int covered = 0, border = 0, xMin = image.width, xMax = -1, yMin = image.height, yMax = -1;
    for (int y = 0; y < image.height; ++y) {
      for (int x = 0; x < image.width; ++x) {
        if (image.same(x, y, background)) continue;
        ++covered;
        if (x == 0 || y == 0 || x == image.width - 1 || y == image.height - 1) ++border;
        xMin = std::min(xMin, x), xMax = std::max(xMax, x), yMin = std::min(yMin, y), yMax = std::max(yMax, y);
      }
    }
    EXPECT_EQ(border, 0);
    EXPECT_GT(covered, image.width * image.height / 30);
    // The subject spans a good part of the picture in at least one direction.
    EXPECT_GT(std::max(static_cast<float>(xMax - xMin) / static_cast<float>(image.width),
                       static_cast<float>(yMax - yMin) / static_cast<float>(image.height)),
              0.4f);
  }
  // Without a camera the options frame the mesh from the front three-quarter view.
  SnapshotOptions automatic;
  automatic.width = 160;
  automatic.height = 120;
  SnapshotOptions framed = automatic;
  framed.camera = frameMesh(mesh, kFrontThreeQuarter, 160.0f / 120.0f);
  EXPECT_EQ(renderMesh(mesh, automatic), renderMesh(mesh, framed));
}

TEST(Snapshot, BadSizeGivesNoPixels) {
  SnapshotOptions options;
  options.width = 0;
  EXPECT_TRUE(renderMesh(Mesh{}, options).empty());
}

class SnapshotFileTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("imps_snapshot_" + std::to_string(::getpid()) + "_" +
                                        testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(SnapshotFileTest, PngReadsBackWithTheRenderedPixels) {
  SnapshotOptions options = frontView(96);
  options.height = 72;
  const Mesh sphere = icosphere(3, 1.0f, glm::vec3(0.0f), kRed);
  const std::string path = (dir_ / "sphere.png").string();
  ASSERT_EQ(test::failureText(renderMeshToPng(sphere, options, path)), "");

  std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in) << OIIO::geterror();
  EXPECT_STREQ(in->format_name(), "png");
  const OIIO::ImageSpec& spec = in->spec();
  EXPECT_EQ(spec.width, 96);
  EXPECT_EQ(spec.height, 72);
  EXPECT_EQ(spec.nchannels, 4);
  EXPECT_EQ(spec.format, OIIO::TypeDesc::UINT8);
  std::vector<uint8_t> pixels(96 * 72 * 4);
  ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, pixels.data())) << in->geterror();
  in->close();
  EXPECT_EQ(pixels, renderMesh(sphere, options));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);  // no temporary left
}

TEST_F(SnapshotFileTest, BadPathsAreErrors) {
  // Both fail as an output not written: one error without a location whose message names the file.
  const auto message = [](const std::expected<void, Diagnostics>& r) {
    if (r) return std::string("saved");
    EXPECT_EQ(r.error().errorCount(), 1);
    EXPECT_EQ(r.error().all().front().loc.file, "");
    return r.error().all().front().message;
  };
  const std::string jpg = (dir_ / "shot.jpg").string(), missing = (dir_ / "missing" / "shot.png").string();
  EXPECT_EQ(message(renderMeshToPng(Mesh{}, SnapshotOptions{}, jpg)), jpg + ": image files must end in .png");
  EXPECT_EQ(message(renderMeshToPng(Mesh{}, SnapshotOptions{}, missing)),
            "cannot save '" + missing + "': creating a temporary file: No such file or directory");
  EXPECT_TRUE(fs::is_empty(dir_));
}

}  // namespace
}  // namespace imps::app
