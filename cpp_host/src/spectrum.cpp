// mfhost — spectra (see spectrum.h).
#include "spectrum.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>

#include "error.h"

namespace mf {

namespace {

constexpr float kCieMin = 360.0f, kCieMax = 830.0f;
constexpr int kCieSamples = 95;  // 5 nm steps
// 1 / (integral of the y colour-matching function of the table): a unit spectrum has Y = 1.
constexpr double kCieYNormalization = 1.0 / 106.7502593994140625;
// 1 / (luminance of the D65 table below): D65 scaled to Y = 1.
constexpr double kCieD65Normalization = 1.0 / 98.99741751876255;

// The CIE 1931 2° standard observer x, y, z at 360, 365, ..., 830 nm (CIE 018:2019 /
// ISO/CIE 11664-1, the 5 nm table that Mitsuba 3 also uses).
const float kCieX[kCieSamples] = {
    0.0001299f, 0.0002321f, 0.0004149f, 0.0007416f, 0.001368f, 0.002236f, 0.004243f, 0.00765f,
    0.01431f, 0.02319f, 0.04351f, 0.07763f, 0.13438f, 0.21477f, 0.2839f, 0.3285f,
    0.34828f, 0.34806f, 0.3362f, 0.3187f, 0.2908f, 0.2511f, 0.19536f, 0.1421f,
    0.09564f, 0.05795001f, 0.03201f, 0.0147f, 0.0049f, 0.0024f, 0.0093f, 0.0291f,
    0.06327f, 0.1096f, 0.1655f, 0.2257499f, 0.2904f, 0.3597f, 0.4334499f, 0.5120501f,
    0.5945f, 0.6784f, 0.7621f, 0.8425f, 0.9163f, 0.9786f, 1.0263f, 1.0567f,
    1.0622f, 1.0456f, 1.0026f, 0.9384f, 0.8544499f, 0.7514f, 0.6424f, 0.5419f,
    0.4479f, 0.3608f, 0.2835f, 0.2187f, 0.1649f, 0.1212f, 0.0874f, 0.0636f,
    0.04677f, 0.0329f, 0.0227f, 0.01584f, 0.01135916f, 0.008110916f, 0.005790346f, 0.004109457f,
    0.002899327f, 0.00204919f, 0.001439971f, 0.0009999493f, 0.0006900786f, 0.0004760213f, 0.0003323011f, 0.0002348261f,
    0.0001661505f, 0.000117413f, 8.307527e-05f, 5.870652e-05f, 4.150994e-05f, 2.935326e-05f, 2.067383e-05f, 1.455977e-05f,
    1.025398e-05f, 7.221456e-06f, 5.085868e-06f, 3.581652e-06f, 2.522525e-06f, 1.776509e-06f, 1.251141e-06f,
};
const float kCieY[kCieSamples] = {
    3.917e-06f, 6.965e-06f, 1.239e-05f, 2.202e-05f, 3.9e-05f, 6.4e-05f, 0.00012f, 0.000217f,
    0.000396f, 0.00064f, 0.00121f, 0.00218f, 0.004f, 0.0073f, 0.0116f, 0.01684f,
    0.023f, 0.0298f, 0.038f, 0.048f, 0.06f, 0.0739f, 0.09098f, 0.1126f,
    0.13902f, 0.1693f, 0.20802f, 0.2586f, 0.323f, 0.4073f, 0.503f, 0.6082f,
    0.71f, 0.7932f, 0.862f, 0.9148501f, 0.954f, 0.9803f, 0.9949501f, 1.0f,
    0.995f, 0.9786f, 0.952f, 0.9154f, 0.87f, 0.8163f, 0.757f, 0.6949f,
    0.631f, 0.5668f, 0.503f, 0.4412f, 0.381f, 0.321f, 0.265f, 0.217f,
    0.175f, 0.1382f, 0.107f, 0.0816f, 0.061f, 0.04458f, 0.032f, 0.0232f,
    0.017f, 0.01192f, 0.00821f, 0.005723f, 0.004102f, 0.002929f, 0.002091f, 0.001484f,
    0.001047f, 0.00074f, 0.00052f, 0.0003611f, 0.0002492f, 0.0001719f, 0.00012f, 8.48e-05f,
    6e-05f, 4.24e-05f, 3e-05f, 2.12e-05f, 1.499e-05f, 1.06e-05f, 7.4657e-06f, 5.2578e-06f,
    3.7029e-06f, 2.6078e-06f, 1.8366e-06f, 1.2934e-06f, 9.1093e-07f, 6.4153e-07f, 4.5181e-07f,
};
const float kCieZ[kCieSamples] = {
    0.0006061f, 0.001086f, 0.001946f, 0.003486f, 0.006450001f, 0.01054999f, 0.02005001f, 0.03621f,
    0.06785001f, 0.1102f, 0.2074f, 0.3713f, 0.6456f, 1.0390501f, 1.3856f, 1.62296f,
    1.74706f, 1.7826f, 1.77211f, 1.7441f, 1.6692f, 1.5281f, 1.28764f, 1.0419f,
    0.8129501f, 0.6162f, 0.46518f, 0.3533f, 0.272f, 0.2123f, 0.1582f, 0.1117f,
    0.07824999f, 0.05725001f, 0.04216f, 0.02984f, 0.0203f, 0.0134f, 0.008749999f, 0.005749999f,
    0.0039f, 0.002749999f, 0.0021f, 0.0018f, 0.001650001f, 0.0014f, 0.0011f, 0.001f,
    0.0008f, 0.0006f, 0.00034f, 0.00024f, 0.00019f, 0.0001f, 4.999999e-05f, 3e-05f,
    2e-05f, 1e-05f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
    0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
    0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
    0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
    0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f,
};
// The CIE standard illuminant D65, relative spectral power (100 at 560 nm), same wavelengths
// (ISO 11664-2 / CIE S 014-2).
const float kD65[kCieSamples] = {
    46.6383f, 49.3637f, 52.0891f, 51.0323f, 49.9755f, 52.3118f, 54.6482f, 68.7015f,
    82.7549f, 87.1204f, 91.486f, 92.4589f, 93.4318f, 90.057f, 86.6823f, 95.7736f,
    104.865f, 110.936f, 117.008f, 117.41f, 117.812f, 116.336f, 114.861f, 115.392f,
    115.923f, 112.367f, 108.811f, 109.082f, 109.354f, 108.578f, 107.802f, 106.296f,
    104.79f, 106.239f, 107.689f, 106.047f, 104.405f, 104.225f, 104.046f, 102.023f,
    100.0f, 98.1671f, 96.3342f, 96.0611f, 95.788f, 92.2368f, 88.6856f, 89.3459f,
    90.0062f, 89.8026f, 89.5991f, 88.6489f, 87.6987f, 85.4936f, 83.2886f, 83.4939f,
    83.6992f, 81.863f, 80.0268f, 80.1207f, 80.2146f, 81.2462f, 82.2778f, 80.281f,
    78.2842f, 74.0027f, 69.7213f, 70.6652f, 71.6091f, 72.979f, 74.349f, 67.9765f,
    61.604f, 65.7448f, 69.8856f, 72.4863f, 75.087f, 69.3398f, 63.5927f, 55.0054f,
    46.4182f, 56.6118f, 66.8054f, 65.0941f, 63.3828f, 63.8434f, 64.304f, 61.8779f,
    59.4519f, 55.7054f, 51.959f, 54.6998f, 57.4406f, 58.8765f, 60.3125f,
};

/// Table index and weight of a wavelength inside [360, 830] nm.
bool cie_lookup(float w, int* i0, float* t) {
    if (!(w >= kCieMin && w <= kCieMax)) return false;
    float x = (w - kCieMin) * (float(kCieSamples - 1) / (kCieMax - kCieMin));
    *i0 = std::min(int(x), kCieSamples - 2);
    *t = x - float(*i0);
    return true;
}

float lerp_table(const float* table, int i0, float t) { return (1.0f - t) * table[i0] + t * table[i0 + 1]; }

double parse_double(const std::string& s, const char* what) {
    const char* p = s.c_str();
    char* end = nullptr;
    errno = 0;
    double v = std::strtod(p, &end);
    while (end && *end && std::isspace((unsigned char)*end)) ++end;
    if (s.empty() || end == p || *end || errno == ERANGE || !std::isfinite(v))
        throw Error(std::string("could not parse ") + what + " " + quote(s, 64));
    return v;
}

void check_spectrum(const SampledSpectrum& s) {
    if (s.wavelengths.size() < 2) throw Error("a spectrum needs at least two wavelength:value pairs");
    for (size_t i = 1; i < s.wavelengths.size(); ++i)
        if (!(s.wavelengths[i] > s.wavelengths[i - 1]))
            throw Error("the wavelengths of a spectrum must increase strictly (" + std::to_string(s.wavelengths[i - 1]) +
                        " is followed by " + std::to_string(s.wavelengths[i]) + ")");
}

}  // namespace

Rgb cie1931_xyz(float w) {
    int i;
    float t;
    if (!cie_lookup(w, &i, &t)) return Rgb(0.0f);
    return Rgb(lerp_table(kCieX, i, t), lerp_table(kCieY, i, t), lerp_table(kCieZ, i, t));
}

float cie_d65(float w) {
    int i;
    float t;
    if (!cie_lookup(w, &i, &t)) return 0.0f;
    return float(lerp_table(kD65, i, t) * kCieD65Normalization);
}

Rgb xyz_to_linear_srgb(const Rgb& c) {
    return Rgb(3.240479f * c.r - 1.537150f * c.g - 0.498535f * c.b, -0.969256f * c.r + 1.875991f * c.g + 0.041556f * c.b,
               0.055648f * c.r - 0.204043f * c.g + 1.057311f * c.b);
}

Rgb sampled_spectrum_to_rgb(const SampledSpectrum& s, SpectrumUse use, bool* clamped) {
    check_spectrum(s);
    const std::vector<double>& wl = s.wavelengths;
    const int steps = 1000;
    double xyz[3] = {0, 0, 0};
    size_t k = 0;  // interval [wl[k], wl[k+1]] holding w (w increases)
    for (int i = 0; i < steps; ++i) {
        double w = kCieMin + (double(i) / (steps - 1)) * (kCieMax - kCieMin);
        if (w < wl.front() || w > wl.back()) continue;
        while (k + 2 < wl.size() && wl[k + 1] <= w) ++k;
        double w0 = wl[k], w1 = wl[k + 1], v0 = s.values[k], v1 = s.values[k + 1];
        double v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        if (use != SpectrumUse::Emission) v *= cie_d65(float(w));
        Rgb c = cie1931_xyz(float(w));
        for (int a = 0; a < 3; ++a) xyz[a] += double(c[a]) * v;
    }
    const double scale = (kCieMax - kCieMin) / steps * kCieYNormalization;
    Rgb rgb = xyz_to_linear_srgb(Rgb(float(xyz[0] * scale), float(xyz[1] * scale), float(xyz[2] * scale)));
    const Rgb raw = rgb;
    for (int c = 0; c < 3; ++c) {
        rgb[c] = std::max(rgb[c], 0.0f);  // out of the sRGB gamut (Mitsuba clamps too)
        if (use == SpectrumUse::Reflectance) rgb[c] = std::min(rgb[c], 1.0f);  // a bounded reflectance
    }
    if (clamped) *clamped = raw.r != rgb.r || raw.g != rgb.g || raw.b != rgb.b;
    return rgb;
}

Rgb constant_spectrum_to_rgb(double value, SpectrumUse use) {
    if (use == SpectrumUse::Emission) return xyz_to_linear_srgb(Rgb(1.0f)) * float(value);
    return Rgb(float(value));
}

SampledSpectrum parse_spectrum_pairs(const std::string& text) {
    SampledSpectrum s;
    size_t i = 0;
    while (i < text.size()) {
        while (i < text.size() && (std::isspace((unsigned char)text[i]) || text[i] == ',')) ++i;
        if (i >= text.size()) break;
        size_t j = i;
        while (j < text.size() && !std::isspace((unsigned char)text[j]) && text[j] != ',') ++j;
        std::string token = text.substr(i, j - i);
        size_t colon = token.find(':');
        if (colon == std::string::npos || token.find(':', colon + 1) != std::string::npos)
            throw Error("invalid spectrum entry " + quote(token, 64) + " (expected wavelength:value)");
        s.wavelengths.push_back(parse_double(token.substr(0, colon), "wavelength"));
        s.values.push_back(parse_double(token.substr(colon + 1), "spectrum value"));
        i = j;
    }
    check_spectrum(s);
    return s;
}

SampledSpectrum read_spectrum_file(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw Error("cannot read spectrum file " + quote(path, 200));
    SampledSpectrum s;
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        size_t hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::vector<std::string> tokens;
        size_t i = 0;
        while (i < line.size()) {
            while (i < line.size() && std::isspace((unsigned char)line[i])) ++i;
            size_t j = i;
            while (j < line.size() && !std::isspace((unsigned char)line[j])) ++j;
            if (j > i) tokens.push_back(line.substr(i, j - i));
            i = j;
        }
        if (tokens.empty()) continue;
        try {
            if (tokens.size() != 2) throw Error("expected \"wavelength value\", got " + std::to_string(tokens.size()) + " fields");
            s.wavelengths.push_back(parse_double(tokens[0], "wavelength"));
            s.values.push_back(parse_double(tokens[1], "spectrum value"));
        } catch (const Error& e) {
            throw Error(path + ":" + std::to_string(line_no) + ": " + e.what());
        }
        if (s.wavelengths.size() > 1000000) throw Error(path + ": more than 10^6 spectrum samples");
    }
    try {
        check_spectrum(s);
    } catch (const Error& e) {
        throw Error(path + ": " + e.what());
    }
    return s;
}

}  // namespace mf
