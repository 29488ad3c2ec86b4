// A tiny C API over OpenImageIO for genpath (src/image/oiio.rs is its only caller).
//
// Written against the OIIO 2.4 API and valid for 2.5. No C++ exception may cross into Rust:
// every entry point catches everything and reports failures as text in `err`.

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

namespace {

// Copies `msg` into the caller's buffer, truncated and always NUL-terminated.
void set_error(char* err, size_t errlen, const std::string& msg)
{
    if (err == nullptr || errlen == 0)
        return;
    size_t n = std::min(msg.size(), errlen - 1);
    std::memcpy(err, msg.data(), n);
    err[n] = '\0';
}

// OIIO reports some failures on the object and some globally; take whichever has text.
std::string oiio_error(const std::string& object_error, const char* fallback)
{
    if (!object_error.empty())
        return object_error;
    std::string global = OIIO::geterror();
    return global.empty() ? std::string(fallback) : global;
}

bool is_float_type(TypeDesc t)
{
    return t.basetype == TypeDesc::FLOAT || t.basetype == TypeDesc::HALF
           || t.basetype == TypeDesc::DOUBLE;
}

}  // namespace

extern "C" {

// 1 if OIIO has a writer for this file name's extension, else 0.
int genpath_oiio_can_write(const char* path)
{
    try {
        auto out = ImageOutput::create(std::string(path));
        OIIO::geterror();  // drop the "no writer" message so it cannot leak into a later error
        return out ? 1 : 0;
    } catch (...) {
        return 0;
    }
}

// Writes a `w`×`h` RGB image. The file's pixel type is the writer's choice for a float request:
// float-capable formats (EXR, TIFF, HDR...) get `linear` unchanged; integer formats (PNG, JPEG...)
// get `srgb8`, which the caller has already sRGB-encoded, clamped and rounded so that every
// back-end produces the same bytes. Returns 0 on success, -1 with a message in `err`.
int genpath_oiio_write_rgb(const char* path, int w, int h, const float* linear,
                           const unsigned char* srgb8, char* err, size_t errlen)
{
    try {
        std::string name(path);
        auto out = ImageOutput::create(name);
        if (!out) {
            set_error(err, errlen, oiio_error("", "no OpenImageIO writer for this file name"));
            return -1;
        }
        ImageSpec spec(w, h, 3, TypeDesc::FLOAT);
        if (!out->open(name, spec)) {
            set_error(err, errlen, oiio_error(out->geterror(), "cannot open for writing"));
            return -1;
        }
        bool ok = is_float_type(out->spec().format)
                      ? out->write_image(TypeDesc::FLOAT, linear)
                      : out->write_image(TypeDesc::UINT8, srgb8);
        // Close even after a failed write so the file handle is released; report the first error.
        std::string write_error = ok ? std::string() : oiio_error(out->geterror(), "write failed");
        bool closed = out->close();
        if (!ok) {
            set_error(err, errlen, write_error);
            return -1;
        }
        if (!closed) {
            set_error(err, errlen, oiio_error(out->geterror(), "close failed"));
            return -1;
        }
        return 0;
    } catch (const std::exception& e) {
        set_error(err, errlen, std::string("OpenImageIO threw: ") + e.what());
        return -1;
    } catch (...) {
        set_error(err, errlen, "OpenImageIO threw an unknown exception");
        return -1;
    }
}

// Reads the first subimage of any OIIO-readable file as RGB floats (grey is replicated; channels
// past the third are dropped). Always sets `*w`, `*h` and `*is_float` (1 when the file stores
// floats, i.e. linear data; 0 for integer files, whose values in [0,1] are display-encoded).
// Returns 0 when the pixels were stored in `out`, 1 when `out_len` (in floats) is smaller than
// w*h*3 — call again with a big enough buffer — and -1 with a message in `err` on failure.
int genpath_oiio_read_rgb(const char* path, float* out, size_t out_len, int* w, int* h,
                          int* is_float, char* err, size_t errlen)
{
    try {
        auto in = ImageInput::open(std::string(path));
        if (!in) {
            set_error(err, errlen, oiio_error("", "cannot open for reading"));
            return -1;
        }
        const ImageSpec& spec = in->spec();
        *w = spec.width;
        *h = spec.height;
        *is_float = is_float_type(spec.format) ? 1 : 0;
        if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth > 1) {
            set_error(err, errlen, "not a 2D image with at least one channel");
            return -1;
        }
        size_t npix = size_t(spec.width) * size_t(spec.height);
        if (out == nullptr || out_len < npix * 3)
            return 1;
        // 2-channel files are grey + alpha, so only 1 or 3 channels are colour.
        int nch = spec.nchannels >= 3 ? 3 : 1;
        std::vector<float> buf(npix * size_t(nch));
        if (!in->read_image(0, 0, 0, nch, TypeDesc::FLOAT, buf.data())) {
            set_error(err, errlen, oiio_error(in->geterror(), "read failed"));
            return -1;
        }
        for (size_t i = 0; i < npix; ++i)
            for (size_t c = 0; c < 3; ++c)
                out[i * 3 + c] = buf[i * size_t(nch) + (nch == 3 ? c : 0)];
        in->close();
        return 0;
    } catch (const std::exception& e) {
        set_error(err, errlen, std::string("OpenImageIO threw: ") + e.what());
        return -1;
    } catch (...) {
        set_error(err, errlen, "OpenImageIO threw an unknown exception");
        return -1;
    }
}

}  // extern "C"
