// PNG encoding of screenshots in memory with OpenImageIO, then the project's atomic file writer.
#include "viewer_screenshot.h"

#include <memory>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include "imps/mesh_io.h"

namespace imps::app {

bool saveScreenshotPng(const std::vector<uint8_t>& pixels, int width, int height, const std::string& path,
                       std::string* error) {
  auto fail = [&](const std::string& reason) {
    if (error) *error = path + ": " + reason;
    return false;
  };
  if (!OIIO::Strutil::iends_with(path, ".png")) return fail("screenshot files must end in .png");
  if (width <= 0 || height <= 0 || pixels.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 4)
    return fail("no pixels to save");
  std::vector<unsigned char> png;
  OIIO::Filesystem::IOVecOutput memory(png);
  std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create("png", &memory);
  if (!out) return fail("OpenImageIO cannot write PNG: " + OIIO::geterror());
  const OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, pixels.data()) || !out->close())
    return fail("PNG encoding failed: " + out->geterror());
  out.reset();
  return writeFileAtomically(path, png, error);
}

}  // namespace imps::app
