// mfhost — images: OpenEXR float RGB read/write, 8-bit sRGB PNG preview.
#pragma once

#include <string>
#include <vector>

namespace mf {

struct Image {
    int width = 0, height = 0;
    std::vector<float> rgb;  // row-major, 3 floats per pixel, top row first
};

/// Read an OpenEXR file into linear RGB (a luminance-only file is expanded to grey).
Image read_exr(const std::string& path);
void write_exr(const std::string& path, const Image& img);
/// Read a texture image: OpenEXR (linear as stored), PNG or JPEG (8/16-bit, the sRGB EOTF is
/// undone unless `raw`, as Mitsuba's bitmap does). Grey and alpha channels: grey is expanded,
/// alpha dropped. Throws mf::Error naming the file.
Image read_texture_image(const std::string& path, bool raw);
float srgb_eotf(float encoded);
/// Tone map (clamp to [0,1] + sRGB OETF) and write an 8-bit RGB PNG.
void write_png_srgb(const std::string& path, const Image& img);
float srgb_oetf(float linear);

}  // namespace mf
