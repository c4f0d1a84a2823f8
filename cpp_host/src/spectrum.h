// mfhost — spectra as Mitsuba 3's RGB variants read them (scalar_rgb, 3.9.1).
//
// A <spectrum> is a constant, a list of wavelength:value pairs (nm, increasing, linear in
// between) or a file of "wavelength value" lines. The RGB variants turn a list into linear
// sRGB once, at load time: 1000 wavelengths evenly spaced over [360, 830] nm (those outside
// the list's range contribute nothing), each weighted by the CIE 1931 2° colour-matching
// functions and, for anything that is not an emitter, by the CIE D65 illuminant (so that a
// reflectance of 1 is white), summed times 470/1000 nm, scaled so that a unit spectrum has
// luminance 1, then the XYZ -> linear sRGB (Rec. 709) matrix. Negative components are clamped
// to 0, and outside emitters and indices of refraction (eta, k, int_ior, ext_ior) components
// above 1 are clamped to 1 (Mitsuba warns and clamps; so does mfrender).
// A constant spectrum is grey outside emitters; in an emitter it is the sRGB colour of an
// equal-energy spectrum, value x (1.2048, 0.9483, 0.9089) (xyz_to_srgb(1, 1, 1)), as Mitsuba
// does so that RGB and spectral renders agree.
#pragma once

#include <string>
#include <vector>

#include "math.h"

namespace mf {

/// A spectrum given as samples: wavelengths (nm, strictly increasing) and values.
struct SampledSpectrum {
    std::vector<double> wavelengths, values;
};

/// Where a spectrum is used decides how the RGB variants convert it.
enum class SpectrumUse { Reflectance, Unbounded, Emission };

/// Mitsuba's conversion of a sampled spectrum to linear sRGB (see above); *clamped (if given)
/// tells whether the colour left the range and was clamped.
Rgb sampled_spectrum_to_rgb(const SampledSpectrum& s, SpectrumUse use, bool* clamped = nullptr);
/// Mitsuba's RGB value of a constant spectrum.
Rgb constant_spectrum_to_rgb(double value, SpectrumUse use);

/// Parse "wl:value, wl:value, ..." (at least two pairs, wavelengths strictly increasing).
/// Throws mf::Error (without location) on malformed input.
SampledSpectrum parse_spectrum_pairs(const std::string& text);
/// Read a spectrum file (Mitsuba's .spd text: one "wavelength value" pair per line, '#'
/// comments and blank lines ignored). Throws mf::Error naming the file and line.
SampledSpectrum read_spectrum_file(const std::string& path);

/// The CIE 1931 2° colour-matching functions at a wavelength (nm; 0 outside [360, 830]):
/// linear interpolation of the 5 nm table.
Rgb cie1931_xyz(float wavelength_nm);
/// The CIE D65 illuminant at a wavelength, normalised to luminance 1 (0 outside [360, 830]).
float cie_d65(float wavelength_nm);
/// CIE XYZ -> linear sRGB (Rec. 709 primaries, D65 white), Mitsuba's matrix.
Rgb xyz_to_linear_srgb(const Rgb& xyz);

}  // namespace mf
