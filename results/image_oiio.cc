// image_oiio.cc - the OpenImageIO adapter: the only C++ on the results side,
// exposing plain C functions.
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <memory>
#include <string>

extern "C" {
#include "image.h"
}

namespace {

bool write_to(const char *path, int w, int h, int channels, OIIO::TypeDesc type, const void *pixels, size_t elem,
              sb_err *err);

// Written under a temporary name with the same extension (OIIO picks the
// format by it), then renamed: a killed run leaves no half-written image.
bool write(const char *path, int w, int h, int channels, OIIO::TypeDesc type, const void *pixels, size_t elem,
           sb_err *err) {
    std::string final_path(path), tmp(path);
    size_t dot = final_path.find_last_of('.'), slash = final_path.find_last_of('/');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) dot = final_path.size();
    tmp.insert(dot, ".tmp");
    bool ok = write_to(tmp.c_str(), w, h, channels, type, pixels, elem, err);
    if (ok && std::rename(tmp.c_str(), path) != 0) ok = sb_fail(err, "%s: cannot rename from %s", path, tmp.c_str());
    if (!ok) std::remove(tmp.c_str());
    return ok;
}

bool write_to(const char *path, int w, int h, int channels, OIIO::TypeDesc type, const void *pixels, size_t elem,
              sb_err *err) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return sb_fail(err, "%s: no image writer for this extension (%s)", path, OIIO::geterror().c_str());
    OIIO::ImageSpec spec(w, h, channels, type);
    if (!out->open(path, spec)) return sb_fail(err, "%s: %s", path, out->geterror().c_str());
    // GL rows are bottom-up: start at the last row and step backwards
    const char *last = static_cast<const char *>(pixels) + (size_t)(h - 1) * w * channels * elem;
    OIIO::stride_t ystride = -(OIIO::stride_t)((size_t)w * channels * elem);
    bool ok = out->write_image(type, last, OIIO::AutoStride, ystride);
    std::string e = ok ? "" : out->geterror();
    out->close();
    if (!ok) return sb_fail(err, "%s: %s", path, e.c_str());
    return true;
}

} // namespace

extern "C" bool sb_image_write_u8(const char *path, int w, int h, int channels, const unsigned char *pixels,
                                  sb_err *err) {
    return write(path, w, h, channels, OIIO::TypeDesc::UINT8, pixels, 1, err);
}

extern "C" bool sb_image_write_f32(const char *path, int w, int h, int channels, const float *pixels, sb_err *err) {
    return write(path, w, h, channels, OIIO::TypeDesc::FLOAT, pixels, 4, err);
}

extern "C" bool sb_images_available(void) { return true; }
