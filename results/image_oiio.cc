// image_oiio.cc - the OpenImageIO adapter: the only C++ on the results side.
// Built as a module of its own (libsbimages.so beside the binary), opened by
// results/image_dl.c only when --images asks for images: OpenImageIO links
// about 250 libraries, and a process that writes no image should not pay for
// loading them. Its one entry point is plain C and uses nothing of the binary.
#include <OpenImageIO/imageio.h>

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <new>
#include <string>

#include <sys/stat.h>

#include "image_module.h"

namespace {

struct sb_err {
    char *msg;
    size_t len;
};

bool sb_fail(sb_err *err, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(err->msg, err->len, fmt, ap);
    va_end(ap);
    return false;
}

bool write_to(const char *path, int w, int h, int channels, OIIO::TypeDesc type, const void *pixels, size_t elem,
              sb_err *err);

// OpenImageIO's message on one line (it may hold several)
std::string one_line(std::string m) {
    while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
    for (char &ch : m)
        if (ch == '\n' || ch == '\r') ch = ';';
    return m;
}

// Written under a temporary name with the same extension (OIIO picks the
// format by it), then renamed: a killed run leaves no half-written image.
bool write(const char *path, int w, int h, int channels, OIIO::TypeDesc type, const void *pixels, size_t elem,
           sb_err *err) {
    std::string final_path(path), tmp(path);
    size_t dot = final_path.find_last_of('.'), slash = final_path.find_last_of('/');
    /* the target's folder first: a missing one is named, not the temporary file it stopped */
    std::string folder = slash == std::string::npos ? "." : slash == 0 ? "/" : final_path.substr(0, slash);
    struct stat st;
    if (stat(folder.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
        return sb_fail(err, "%s: no such folder %s", path, folder.c_str());
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
    if (!out->open(path, spec)) return sb_fail(err, "%s: %s", path, one_line(out->geterror()).c_str());
    // GL rows are bottom-up: start at the last row and step backwards
    const char *last = static_cast<const char *>(pixels) + (size_t)(h - 1) * w * channels * elem;
    OIIO::stride_t ystride = -(OIIO::stride_t)((size_t)w * channels * elem);
    bool ok = out->write_image(type, last, OIIO::AutoStride, ystride);
    std::string e = ok ? "" : one_line(out->geterror());
    out->close();
    if (!ok) return sb_fail(err, "%s: %s", path, e.c_str());
    return true;
}

} // namespace

extern "C" bool SB_IMAGE_MODULE_READ_ENTRY(const char *path, int *w, int *h, float **pixels, char *err, size_t err_len) {
    sb_err e{err, err_len};
    *pixels = nullptr;
    OIIO::ImageSpec hints;
    hints.attribute("oiio:UnassociatedAlpha", 1);   /* values as stored: an alpha channel is never multiplied in */
    auto in = OIIO::ImageInput::open(path, &hints);
    if (!in) return sb_fail(&e, "%s: cannot read: %s", path, one_line(OIIO::geterror()).c_str());
    const OIIO::ImageSpec &spec = in->spec();
    int nc = spec.nchannels;
    if (spec.width <= 0 || spec.height <= 0 || nc < 1 || spec.depth > 1) {
        in->close();
        return sb_fail(&e, "%s: not a 2D image (%dx%d, %d channels)", path, spec.width, spec.height, nc);
    }
    /* the header's size against the limit before anything is allocated (a header may claim what no data backs) */
    if ((double)spec.width * spec.height > SB_IMAGE_MAX_PIXELS || nc > 16) {
        in->close();
        return sb_fail(&e, "%s: %dx%d with %d channels: more than the %.0f pixels (16384 x 16384) and 16 channels "
                       "an image may have here", path, spec.width, spec.height, nc, (double)SB_IMAGE_MAX_PIXELS);
    }
    struct stat st;
    double stored = (double)spec.width * spec.height * nc * spec.format.size();
    if (stat(path, &st) == 0 && stored > SB_IMAGE_RATIO_FLOOR && stored > SB_IMAGE_MAX_RATIO * (double)st.st_size) {
        in->close();
        return sb_fail(&e, "%s: its header claims %dx%d with %d channels (%.0f bytes) in a file of %lld bytes: more "
                       "than %.0f bytes a byte, which no image format packs", path, spec.width, spec.height, nc,
                       stored, (long long)st.st_size, SB_IMAGE_MAX_RATIO);
    }
    std::unique_ptr<float[]> all(new (std::nothrow) float[(size_t)spec.width * spec.height * nc]);
    if (!all) {
        in->close();
        return sb_fail(&e, "%s: out of memory for %dx%d", path, spec.width, spec.height);
    }
    bool ok = in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, all.get());
    std::string why = ok ? "" : one_line(in->geterror());
    in->close();
    if (!ok) return sb_fail(&e, "%s: %s", path, why.c_str());
    size_t n = (size_t)spec.width * spec.height;
    float *rgb = static_cast<float *>(std::malloc(sizeof(float) * 3 * (n ? n : 1)));
    if (!rgb) return sb_fail(&e, "%s: out of memory", path);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) rgb[3 * i + c] = all[i * nc + (nc >= 3 ? c : 0)];
    *w = spec.width, *h = spec.height, *pixels = rgb;
    return true;
}

extern "C" bool SB_IMAGE_MODULE_ENTRY(const char *path, int w, int h, int channels, int is_float, const void *pixels,
                                      char *err, size_t err_len) {
    sb_err e{err, err_len};
    return is_float ? write(path, w, h, channels, OIIO::TypeDesc::FLOAT, pixels, 4, &e)
                    : write(path, w, h, channels, OIIO::TypeDesc::UINT8, pixels, 1, &e);
}
