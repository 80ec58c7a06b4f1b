// SPDX-License-Identifier: MIT
// Checks two screenshots of the live app (`puppeteer view`, HUD off): both show a character (not blank), they
// have the same size, and they differ only where the posed limb moved — in the upper body, on the screen's
// right half (the character's left arm seen from the front three-quarter camera), not in the legs.
// Usage: viewer_shot_check REST.png POSED.png [LEGS]: LEGS (default 0.02) is the largest fraction of the differing
// pixels allowed in the bottom 40% of the image (the particle tesselator's triangulation there varies a little with
// the number of settling updates, Marching Cubes' does not). Exit 0 when every check passes; prints what failed
// otherwise.
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace {

struct Image {
  int width = 0, height = 0, channels = 0;
  std::vector<unsigned char> pixels;
  const unsigned char* at(int x, int y) const {
    return &pixels[(static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) *
                   static_cast<size_t>(channels)];
  }
};

bool load(const std::string& path, Image& image) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    std::fprintf(stderr, "%s: cannot open: %s\n", path.c_str(), OIIO::geterror().c_str());
    return false;
  }
  const OIIO::ImageSpec& spec = in->spec();
  image.width = spec.width, image.height = spec.height, image.channels = spec.nchannels;
  image.pixels.resize(static_cast<size_t>(image.width) * static_cast<size_t>(image.height) *
                      static_cast<size_t>(image.channels));
  return in->read_image(0, 0, 0, image.channels, OIIO::TypeDesc::UINT8, image.pixels.data());
}

bool differs(const unsigned char* a, const unsigned char* b, int threshold) {
  for (int c = 0; c < 3; ++c)
    if (std::abs(int(a[c]) - int(b[c])) > threshold) return true;
  return false;
}

// Fraction of pixels unlike their row's background (the gradient is vertical: the right-most pixel of the row).
double foreground(const Image& image) {
  size_t n = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
      if (differs(image.at(x, y), image.at(image.width - 1, y), 12)) ++n;
  return double(n) / (double(image.width) * double(image.height));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr, "usage: viewer_shot_check REST.png POSED.png [LEGS]\n");
    return 2;
  }
  const double legsAllowed = argc == 4 ? std::atof(argv[3]) : 0.02;
  Image rest, posed;
  if (!load(argv[1], rest) || !load(argv[2], posed)) return 1;
  int failures = 0;
  auto check = [&](bool ok, const std::string& what) {
    std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what.c_str());
    if (!ok) ++failures;
  };
  check(rest.width == posed.width && rest.height == posed.height && rest.channels >= 3 &&
            rest.channels == posed.channels,
        "same size: " + std::to_string(rest.width) + "x" + std::to_string(rest.height) + " vs " +
            std::to_string(posed.width) + "x" + std::to_string(posed.height));
  if (failures) return 1;
  const double fgRest = foreground(rest), fgPosed = foreground(posed);
  check(fgRest > 0.02 && fgRest < 0.6, "rest shot shows a character: " + std::to_string(100 * fgRest) + "% foreground");
  check(fgPosed > 0.02 && fgPosed < 0.6,
        "posed shot shows a character: " + std::to_string(100 * fgPosed) + "% foreground");

  // Where the two differ.
  size_t diff = 0, legs = 0;
  double cx = 0, cy = 0;
  for (int y = 0; y < rest.height; ++y)
    for (int x = 0; x < rest.width; ++x)
      if (differs(rest.at(x, y), posed.at(x, y), 24)) {
        ++diff;
        cx += x, cy += y;
        if (y > rest.height * 6 / 10) ++legs;
      }
  const double total = double(rest.width) * double(rest.height);
  check(double(diff) > 0.003 * total, "the shots differ: " + std::to_string(diff) + " pixels");
  if (diff > 0) {
    cx /= double(diff), cy /= double(diff);
    check(cx > 0.5 * rest.width && cy < 0.6 * rest.height,
          "the difference is centred on the upper right (the moved left arm): centroid " + std::to_string(int(cx)) +
              "," + std::to_string(int(cy)));
    check(double(legs) <= legsAllowed * double(diff),
          "the legs did not change: " + std::to_string(legs) + " pixels below 60%");
  }
  return failures == 0 ? 0 : 1;
}
