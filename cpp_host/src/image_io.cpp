// mfhost — image I/O (see image_io.h).
#include "image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <exception>

#include "error.h"

namespace mf {

Image read_exr(const std::string& path) {
    try {
        Imf::InputFile file(path.c_str());
        Imath::Box2i dw = file.header().dataWindow();
        Image img;
        img.width = dw.max.x - dw.min.x + 1;
        img.height = dw.max.y - dw.min.y + 1;
        if (img.width <= 0 || img.height <= 0) throw Error("OpenEXR file \"" + path + "\" has an empty data window");
        size_t n = size_t(img.width) * size_t(img.height);
        img.rgb.assign(n * 3, 0.0f);
        const Imf::ChannelList& ch = file.header().channels();
        bool has_rgb = ch.findChannel("R") && ch.findChannel("G") && ch.findChannel("B");
        bool has_y = ch.findChannel("Y") != nullptr;
        if (!has_rgb && !has_y) throw Error("OpenEXR file \"" + path + "\" has neither R,G,B nor Y channels");
        Imf::FrameBuffer fb;
        char* base = reinterpret_cast<char*>(img.rgb.data()) -
                     (ptrdiff_t(dw.min.x) + ptrdiff_t(dw.min.y) * img.width) * ptrdiff_t(3 * sizeof(float));
        size_t xs = 3 * sizeof(float), ys = xs * size_t(img.width);
        if (has_rgb) {
            fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
            fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
            fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
        } else {
            fb.insert("Y", Imf::Slice(Imf::FLOAT, base, xs, ys));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        if (!has_rgb)
            for (size_t i = 0; i < n; ++i) img.rgb[3 * i + 1] = img.rgb[3 * i + 2] = img.rgb[3 * i];
        for (float& v : img.rgb)
            if (!std::isfinite(v)) throw Error("OpenEXR file \"" + path + "\" contains non-finite pixel values");
        return img;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error("cannot read OpenEXR file \"" + path + "\": " + e.what());
    }
}

void write_exr(const std::string& path, const Image& img) {
    try {
        Imf::Header header(img.width, img.height);
        header.channels().insert("R", Imf::Channel(Imf::FLOAT));
        header.channels().insert("G", Imf::Channel(Imf::FLOAT));
        header.channels().insert("B", Imf::Channel(Imf::FLOAT));
        header.compression() = Imf::ZIP_COMPRESSION;
        Imf::OutputFile file(path.c_str(), header, 1);
        Imf::FrameBuffer fb;
        char* base = const_cast<char*>(reinterpret_cast<const char*>(img.rgb.data()));
        size_t xs = 3 * sizeof(float), ys = xs * size_t(img.width);
        fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
        fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
        fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
        file.setFrameBuffer(fb);
        file.writePixels(img.height);
    } catch (const std::exception& e) {
        throw Error("cannot write OpenEXR file \"" + path + "\": " + e.what());
    }
}

float srgb_oetf(float v) {
    v = std::clamp(v, 0.0f, 1.0f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

namespace {
void png_error_fn(png_structp png, png_const_charp msg) {
    std::fprintf(stderr, "mfrender: libpng: %s\n", msg);
    png_longjmp(png, 1);
}
void png_warn_fn(png_structp, png_const_charp) {}
}  // namespace

void write_png_srgb(const std::string& path, const Image& img) {
    std::vector<unsigned char> rows(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < rows.size(); ++i) {
        float v = img.rgb[i];
        if (!std::isfinite(v)) v = 0.0f;
        rows[i] = (unsigned char)std::lround(srgb_oetf(v) * 255.0f);
    }
    FILE* fp = std::fopen(path.c_str(), "wb");
    if (!fp) throw Error("cannot open \"" + path + "\" for writing");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, png_error_fn, png_warn_fn);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
        if (png) png_destroy_write_struct(&png, nullptr);
        std::fclose(fp);
        throw Error("libpng initialisation failed");
    }
    std::vector<png_bytep> ptrs(size_t(img.height));
    for (int y = 0; y < img.height; ++y) ptrs[size_t(y)] = rows.data() + size_t(y) * img.width * 3;
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        std::fclose(fp);
        throw Error("cannot write PNG file \"" + path + "\"");
    }
    png_init_io(png, fp);
    png_set_IHDR(png, info, png_uint_32(img.width), png_uint_32(img.height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    png_write_image(png, ptrs.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    if (std::fclose(fp) != 0) throw Error("cannot write PNG file \"" + path + "\"");
}

}  // namespace mf
