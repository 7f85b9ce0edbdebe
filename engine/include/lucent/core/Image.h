// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Linear float RGB images and their files: PNG (8-bit sRGB, tone-mapped) and OpenEXR
/// (linear half or float). Row 0 is the top row of the picture.

#include <lucent/core/FileIO.h>  // writeFileAtomically, for callers that write images themselves
#include <lucent/core/Types.h>

#include <string>
#include <vector>

namespace lucent {

/// Linear RGB float image, row-major, top row first.
class ImageRgb {
public:
    ImageRgb() = default;
    ImageRgb(int width, int height, Rgb fill = Rgb(0.f));

    [[nodiscard]] int width() const { return m_width; }
    [[nodiscard]] int height() const { return m_height; }
    [[nodiscard]] bool isEmpty() const { return m_pixels.empty(); }
    Rgb& at(int x, int y) { return m_pixels[size_t(y) * m_width + x]; }
    [[nodiscard]] const Rgb& at(int x, int y) const { return m_pixels[size_t(y) * m_width + x]; }
    std::vector<Rgb>& pixels() { return m_pixels; }
    [[nodiscard]] const std::vector<Rgb>& pixels() const { return m_pixels; }

private:
    int m_width = 0;
    int m_height = 0;
    std::vector<Rgb> m_pixels;
};

/// Tone mapping applied before 8-bit output.
struct ToneMap {
    float exposure = 1.f;  ///< multiplies linear values before the curve
    enum class Curve { Clamp, Reinhard, Aces } curve = Curve::Clamp;
};

/// Maps a linear value to display [0,1] (exposure, curve) and applies the sRGB OETF.
Rgb toneMapToDisplay(const Rgb& linear, const ToneMap& tm);

/// Writes an 8-bit sRGB PNG after tone mapping. Atomic and checked (lucent/core/FileIO.h): on
/// any failure (disk full, read-only folder) an existing file is kept.
/// @throw IoError naming the path on failure.
void writePng(const ImageRgb& image, const std::string& path, const ToneMap& tm = {});

/// Writes a linear OpenEXR file with R, G, B channels (32-bit float). Extra single-channel
/// layers (e.g. per-pixel variance "variance.R") may be added by name. Atomic.
/// @throw IoError naming the path on failure.
void writeExr(const ImageRgb& image, const std::string& path);

/// Writes RGB plus named extra RGB layers (layer "variance" → channels variance.R/G/B).
void writeExrLayers(const ImageRgb& image,
                    const std::vector<std::pair<std::string, const ImageRgb*>>& layers,
                    const std::string& path);

/// Reads the R, G, B channels (or a named layer's) of an OpenEXR file.
/// @throw IoError if the file is missing, malformed, lacks the channels or is larger than the
/// import limits (lucent/core/FileIO.h).
ImageRgb readExr(const std::string& path, const std::string& layer = "");

/// Reads an 8-bit PNG, converting sRGB to linear. @throw IoError on failure.
ImageRgb readPng(const std::string& path);

}  // namespace lucent
