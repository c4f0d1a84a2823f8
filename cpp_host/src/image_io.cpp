// mfhost — image I/O (see image_io.h).
#include "image_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <png.h>
#include <jpeglib.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstring>
#include <cctype>
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

float srgb_eotf(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

namespace {

bool has_ext(const std::string& path, const char* ext) {
    size_t n = std::strlen(ext);
    if (path.size() < n) return false;
    for (size_t i = 0; i < n; ++i)
        if (std::tolower((unsigned char)path[path.size() - n + i]) != ext[i]) return false;
    return true;
}

Image read_png_rgb(const std::string& path) {
    png_image im;
    std::memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&im, path.c_str()))
        throw Error("cannot read PNG file \"" + path + "\": " + im.message);
    im.format = PNG_FORMAT_RGB;
    if (im.width == 0 || im.height == 0 || im.width > 65536 || im.height > 65536) {
        png_image_free(&im);
        throw Error("PNG file \"" + path + "\" has an unsupported size");
    }
    std::vector<unsigned char> buf(PNG_IMAGE_SIZE(im));
    if (!png_image_finish_read(&im, nullptr, buf.data(), 0, nullptr)) {
        std::string msg = im.message;
        png_image_free(&im);
        throw Error("cannot read PNG file \"" + path + "\": " + msg);
    }
    Image img;
    img.width = int(im.width);
    img.height = int(im.height);
    img.rgb.resize(buf.size());
    for (size_t i = 0; i < buf.size(); ++i) img.rgb[i] = float(buf[i]) / 255.0f;
    return img;
}

struct JpegError {
    jpeg_error_mgr mgr;
    jmp_buf jump;
};

void jpeg_fail(j_common_ptr cinfo) {
    longjmp(reinterpret_cast<JpegError*>(cinfo->err)->jump, 1);
}

Image read_jpeg_rgb(const std::string& path) {
    FILE* fp = std::fopen(path.c_str(), "rb");
    if (!fp) throw Error("cannot open JPEG file \"" + path + "\"");
    jpeg_decompress_struct cinfo;
    JpegError err;
    cinfo.err = jpeg_std_error(&err.mgr);
    err.mgr.error_exit = jpeg_fail;
    Image img;
    std::vector<unsigned char> row;
    if (setjmp(err.jump)) {
        jpeg_destroy_decompress(&cinfo);
        std::fclose(fp);
        throw Error("cannot read JPEG file \"" + path + "\"");
    }
    jpeg_create_decompress(&cinfo);
    jpeg_stdio_src(&cinfo, fp);
    jpeg_read_header(&cinfo, TRUE);
    cinfo.out_color_space = JCS_RGB;
    jpeg_start_decompress(&cinfo);
    if (cinfo.output_width > 65536 || cinfo.output_height > 65536 || cinfo.output_components != 3) longjmp(err.jump, 1);
    img.width = int(cinfo.output_width);
    img.height = int(cinfo.output_height);
    img.rgb.resize(size_t(img.width) * img.height * 3);
    row.resize(size_t(img.width) * 3);
    while (cinfo.output_scanline < cinfo.output_height) {
        unsigned char* r = row.data();
        size_t y = cinfo.output_scanline;
        jpeg_read_scanlines(&cinfo, &r, 1);
        for (size_t i = 0; i < row.size(); ++i) img.rgb[y * row.size() + i] = float(row[i]) / 255.0f;
    }
    jpeg_finish_decompress(&cinfo);
    jpeg_destroy_decompress(&cinfo);
    std::fclose(fp);
    return img;
}

}  // namespace

Image read_texture_image(const std::string& path, bool raw) {
    if (has_ext(path, ".exr")) return read_exr(path);
    Image img;
    if (has_ext(path, ".png")) img = read_png_rgb(path);
    else if (has_ext(path, ".jpg") || has_ext(path, ".jpeg")) img = read_jpeg_rgb(path);
    else throw Error("unsupported image format of \"" + path + "\" (supported: .exr, .png, .jpg)");
    if (!raw)
        for (float& v : img.rgb) v = srgb_eotf(v);
    return img;
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
