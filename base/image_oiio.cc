// image_oiio.cc - the OpenImageIO adapter: the only C++ of the base layer.
// Built as a module of its own (libsbimages.so beside the binary), opened by
// base/image_dl.c only when --images asks for images: OpenImageIO links
// about 250 libraries, and a process that writes no image should not pay for
// loading them. Its one entry point is plain C and uses nothing of the binary.
#include <OpenImageIO/imageio.h>

#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
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

// A null-terminated text of at most max bytes from f (false: the file ended first, or it is longer).
bool read_cstr(std::FILE *f, size_t max, std::string *out) {
    out->clear();
    for (int c; (c = std::fgetc(f)) != EOF;) {
        if (c == 0) return true;
        if (out->size() >= max) return false;
        out->push_back((char)c);
    }
    return false;
}

// The bytes OpenEXR reads for a value of this type at f's place: a fixed size for most types, a channel list's
// entries up to its empty name, a preview's 8 bytes and its pixels; the declared size for a text, a text list and a
// type it does not know (read as declared). -1: a value cut short or not of its type. f's place is left anywhere.
long long value_bytes(std::FILE *f, const std::string &type, long long declared, long long left) {
    static const struct { const char *type; int bytes; } fixed[] = {
        {"box2i", 16}, {"box2f", 16}, {"compression", 1}, {"lineOrder", 1}, {"float", 4}, {"int", 4},
        {"double", 8}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16}, {"v3i", 12}, {"v3f", 12}, {"v3d", 24}, {"m33f", 36},
        {"m33d", 72}, {"m44f", 64}, {"m44d", 128}, {"chromaticities", 32}, {"envmap", 1}, {"keycode", 28},
        {"timecode", 8}, {"rational", 8}, {"tiledesc", 9}, {"deepImageState", 1}, {"floatvector", -1}};
    for (const auto &t : fixed)
        if (type == t.type) return t.bytes < 0 ? declared : t.bytes;
    if (type == "chlist") {   /* name, then pixel type, linear, 3 reserved, x and y sampling: 16 bytes */
        long long n = 0;
        std::string ch;
        for (;;) {
            if (!read_cstr(f, 255, &ch)) return -1;
            n += (long long)ch.size() + 1;
            if (ch.empty()) return n;
            if (std::fseek(f, 16, SEEK_CUR) != 0) return -1;
            n += 16;
            if (n > left) return -1;
        }
    }
    if (type == "preview") {   /* width, height, then 4 bytes a pixel (allocated before they are read) */
        unsigned char wh[8];
        if (std::fread(wh, 1, 8, f) != 8) return -1;
        unsigned long long w = wh[0] | wh[1] << 8 | wh[2] << 16 | (unsigned long long)wh[3] << 24;
        unsigned long long h = wh[4] | wh[5] << 8 | wh[6] << 16 | (unsigned long long)wh[7] << 24;
        return w * h > (unsigned long long)left ? -1 : 8 + 4 * (long long)(w * h);
    }
    return declared;   /* string, stringvector, and any other type: read as declared */
}

// An OpenEXR header's attributes each declare their value's size, and OpenEXR allocates that much before it
// reads the value (a fuzzed 60-byte file declared 1.9 GB): each declared size is checked against the bytes the
// file has left first. True for a file that is no OpenEXR file (its own reader answers for it).
bool exr_header_fits(const char *path, long long file_size, std::string *why) {
    std::FILE *f = std::fopen(path, "rb");
    if (!f) return true;
    unsigned char head[8];
    bool ok = true;
    if (std::fread(head, 1, 8, f) == 8 && head[0] == 0x76 && head[1] == 0x2f && head[2] == 0x31 && head[3] == 0x01) {
        bool multipart = head[5] & 0x10;   /* version field bit 12 */
        std::string name, type;
        for (bool first = true;;) {   /* first: the next name opens a header (an empty one ends a multi-part list) */
            if (!read_cstr(f, 255, &name)) {
                *why = "its header is cut short";
                ok = false;
                break;
            }
            if (name.empty()) {
                if (!multipart || first) break;
                first = true;
                continue;
            }
            first = false;
            unsigned char sz[4];
            if (!read_cstr(f, 255, &type) || std::fread(sz, 1, 4, f) != 4) {
                *why = "its header is cut short";
                ok = false;
                break;
            }
            long long size = (long long)(int32_t)(sz[0] | sz[1] << 8 | sz[2] << 16 | (uint32_t)sz[3] << 24);
            long long at = std::ftell(f), left = file_size - at;
            for (char &ch : name)
                if ((unsigned char)ch < 32 || (unsigned char)ch > 126) ch = '?';   /* said on one line */
            if (size < 0 || size > left) {
                *why = "its header's attribute '" + name + "' declares " + std::to_string(size) + " bytes, and " +
                       std::to_string(left < 0 ? 0 : left) + " follow in the file";
                ok = false;
                break;
            }
            /* OpenEXR reads a value of a known type by its type, not by the declared size: where the two differ it
               goes on from another place than the next attribute (a channel list of 19 declared bytes read further,
               then a string of 1.7 GB allocated); such a header is refused, so the checker's place is OpenEXR's */
            long long reads = value_bytes(f, type, size, left);
            if (reads != size) {
                *why = "its header's attribute '" + name + "' declares " + std::to_string(size) + " bytes for a " +
                       (type.size() < 40 ? type : "value") + ", which is " +
                       (reads < 0 ? std::string("no value of its type") : std::to_string(reads) + " bytes");
                ok = false;
                break;
            }
            std::fseek(f, (long)(at + size), SEEK_SET);
        }
    }
    std::fclose(f);
    return ok;
}

// Whether the folder a file is to be written in exists and is one (false: said, naming it).
bool folder_is_there(const char *path, sb_err *err) {
    std::string p(path);
    size_t slash = p.find_last_of('/');
    std::string folder = slash == std::string::npos ? "." : slash == 0 ? "/" : p.substr(0, slash);
    struct stat st;
    if (stat(folder.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) return true;
    return sb_fail(err, "%s: no such folder %s", path, folder.c_str());
}

// Written under a temporary name with the same extension (OIIO picks the
// format by it), then renamed: a killed run leaves no half-written image.
bool write(const char *path, int w, int h, int channels, OIIO::TypeDesc type, const void *pixels, size_t elem,
           sb_err *err) {
    std::string final_path(path), tmp(path);
    size_t dot = final_path.find_last_of('.'), slash = final_path.find_last_of('/');
    /* the target's folder first: a missing one is named, not the temporary file it stopped */
    if (!folder_is_there(path, err)) return false;
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
    OIIO::ImageSpec hints, spec;
    hints.attribute("oiio:UnassociatedAlpha", 1);   /* values as stored: an alpha channel is never multiplied in */
    /* the reader its extension names, and no other: given the file, OpenImageIO tries every format on one its
       own reader refuses (DICOM's among them, whose dictionary took a fuzzed .exr past 2 GB); given the
       extension alone, it makes that format's reader */
    const char *dot = std::strrchr(path, '.'), *slash = std::strrchr(path, '/');
    if (!dot || (slash && dot < slash) || !dot[1])
        return sb_fail(&e, "%s: no extension to tell its image format by (.png, .exr, ...)", path);
    struct stat fst;
    std::string bad;
    if (stat(path, &fst) == 0 && !exr_header_fits(path, (long long)fst.st_size, &bad))
        return sb_fail(&e, "%s: cannot read: %s", path, bad.c_str());
    auto in = OIIO::ImageInput::create(dot + 1, false, &hints);
    if (!in) return sb_fail(&e, "%s: no image reader for its extension (%s)", path, one_line(OIIO::geterror()).c_str());
    if (!in->open(path, spec, hints)) {
        std::string why = one_line(in->geterror());
        return sb_fail(&e, "%s: cannot read: %s", path, why.empty() ? "not an image of its extension's format" : why.c_str());
    }
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

extern "C" bool SB_IMAGE_MODULE_CAN_WRITE_ENTRY(const char *path, char *err, size_t err_len) {
    sb_err e{err, err_len};
    if (!folder_is_there(path, &e)) return false;
    /* the writer its extension names is made, nothing is opened (a name without one names no writer) */
    const char *dot = std::strrchr(path, '.'), *slash = std::strrchr(path, '/');
    std::string ext = dot && (!slash || dot > slash) ? dot + 1 : "";
    if (ext.empty() || !OIIO::ImageOutput::create(ext))
        return sb_fail(&e, "%s: no image writer for the extension .%s", path, ext.c_str());
    return true;
}
