// SPDX-License-Identifier: MIT
#include <lucent/core/Image.h>

#include <lucent/core/Error.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <png.h>

#include <csetjmp>
#include <filesystem>
#include <memory>

namespace lucent {

ImageRgb::ImageRgb(int width, int height, Rgb fill) : m_width(width), m_height(height) {
    LUCENT_CHECK(width > 0 && height > 0 && width <= 32768 && height <= 32768, "image size ", width,
                 "x", height, " is out of range (1..32768)");
    m_pixels.assign(size_t(width) * height, fill);
}

namespace {

float srgbOetf(float v) {
    v = std::clamp(v, 0.f, 1.f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

float srgbEotf(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

// ACES filmic fit (Narkowicz 2015).
float acesFit(float x) {
    return std::clamp((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f), 0.f, 1.f);
}

}  // namespace

Rgb toneMapToDisplay(const Rgb& linear, const ToneMap& tm) {
    Rgb out;
    for (int c = 0; c < 3; ++c) {
        float v = std::isfinite(linear[c]) ? std::max(linear[c], 0.f) * tm.exposure : 0.f;
        switch (tm.curve) {
            case ToneMap::Curve::Clamp:
                break;
            case ToneMap::Curve::Reinhard:
                v = v / (1.f + v);
                break;
            case ToneMap::Curve::Aces:
                v = acesFit(v);
                break;
        }
        out[c] = srgbOetf(v);
    }
    return out;
}

namespace {

/// libpng output callbacks on a checked sink: a failed write is kept by the sink and reported
/// through png_error (libpng's own error path; no C++ exception crosses the C library).
void pngWrite(png_structp png, png_bytep data, png_size_t n) {
    auto* sink = static_cast<FileSink*>(png_get_io_ptr(png));
    if (!sink->tryWrite(data, n))
        png_error(png, "write failed");
}
void pngFlush(png_structp) {}

/// OpenEXR output on a checked sink. OpenEXR writes its line-offset table from the
/// OutputFile destructor and swallows exceptions there, so failures are also kept by the
/// sink and checked after the OutputFile is gone.
class ExrSinkStream : public Imf::OStream {
public:
    ExrSinkStream(FileSink& sink, const std::string& path)
        : Imf::OStream(path.c_str()), m_sink(sink) {}
    void write(const char c[], int n) override { m_sink.write(c, size_t(n)); }
    uint64_t tellp() override { return m_sink.position(); }
    void seekp(uint64_t pos) override { m_sink.seek(pos); }

private:
    FileSink& m_sink;
};

}  // namespace

void writePng(const ImageRgb& image, const std::string& path, const ToneMap& tm) {
    LUCENT_CHECK(!image.isEmpty(), "cannot write an empty image to '", path, "'");
    writeStreamAtomically(path, [&](FileSink& sink) {
        png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
        png_infop info = png ? png_create_info_struct(png) : nullptr;
        if (!png || !info) {
            png_destroy_write_struct(&png, nullptr);
            LUCENT_THROW(IoError, "libpng could not start writing '", path, "'");
        }
        std::vector<uint8_t> row(size_t(image.width()) * 3);
        if (setjmp(png_jmpbuf(png))) {
            png_destroy_write_struct(&png, &info);
            if (sink.failed())
                throw IoError(sink.error());
            LUCENT_THROW(IoError, "libpng failed while writing '", path, "'");
        }
        png_set_write_fn(png, &sink, pngWrite, pngFlush);
        png_set_IHDR(png, info, image.width(), image.height(), 8, PNG_COLOR_TYPE_RGB,
                     PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
        png_write_info(png, info);
        for (int y = 0; y < image.height(); ++y) {
            for (int x = 0; x < image.width(); ++x) {
                const Rgb d = toneMapToDisplay(image.at(x, y), tm);
                for (int c = 0; c < 3; ++c)
                    row[size_t(x) * 3 + c] = uint8_t(d[c] * 255.f + 0.5f);
            }
            png_write_row(png, row.data());
        }
        png_write_end(png, nullptr);
        png_destroy_write_struct(&png, &info);
    });
}

namespace {
/// Rejects images whose decoded float RGB copy (12 bytes a pixel) would exceed the import
/// limits, before it is allocated.
void checkDecodedImage(const std::string& path, int64_t width, int64_t height) {
    if (width < 1 || height < 1 || width > 32768 || height > 32768)
        LUCENT_THROW(IoError, "image '", path, "' has an invalid size ", width, "x", height,
                     " (1..32768 per side)");
    const uint64_t bytes = uint64_t(width) * uint64_t(height) * sizeof(Rgb);
    if (bytes > importLimits().maxDecodedBytes)
        LUCENT_THROW(IoError, "image '", path, "' (", width, "x", height, ") decodes to ", bytes,
                     " bytes, more than the import limit of ", importLimits().maxDecodedBytes);
}
}  // namespace

ImageRgb readPng(const std::string& path) {
    checkInputFile(path, "PNG file");
    png_image img{};
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&img, path.c_str()))
        LUCENT_THROW(IoError, "cannot read PNG '", path, "': ", img.message);
    try {
        checkDecodedImage(path, img.width, img.height);
    } catch (...) {
        png_image_free(&img);  // begin_read holds libpng's structures until finish_read
        throw;
    }
    img.format = PNG_FORMAT_RGB;
    std::vector<uint8_t> buf(PNG_IMAGE_SIZE(img));
    if (!png_image_finish_read(&img, nullptr, buf.data(), 0, nullptr))
        LUCENT_THROW(IoError, "cannot decode PNG '", path, "': ", img.message);
    ImageRgb out(int(img.width), int(img.height));
    for (size_t i = 0; i < out.pixels().size(); ++i)
        for (int c = 0; c < 3; ++c)
            out.pixels()[i][c] = srgbEotf(buf[i * 3 + c] / 255.f);
    return out;
}

void writeExrLayers(const ImageRgb& image,
                    const std::vector<std::pair<std::string, const ImageRgb*>>& layers,
                    const std::string& path) {
    LUCENT_CHECK(!image.isEmpty(), "cannot write an empty image to '", path, "'");
    for (const auto& [name, layer] : layers)
        LUCENT_CHECK(layer && layer->width() == image.width() && layer->height() == image.height(),
                     "EXR layer '", name, "' does not match the image size");
    writeStreamAtomically(path, [&](FileSink& sink) {
        try {
            Imf::Header header(image.width(), image.height());
            Imf::FrameBuffer fb;
            const size_t xs = sizeof(Rgb), ys = sizeof(Rgb) * size_t(image.width());
            auto addLayer = [&](const std::string& prefix, const ImageRgb& img) {
                const char* names[3] = {"R", "G", "B"};
                for (int c = 0; c < 3; ++c) {
                    const std::string ch = prefix.empty() ? names[c] : prefix + "." + names[c];
                    header.channels().insert(ch, Imf::Channel(Imf::FLOAT));
                    char* base =
                        const_cast<char*>(reinterpret_cast<const char*>(img.pixels().data())) +
                        c * sizeof(float);
                    fb.insert(ch, Imf::Slice(Imf::FLOAT, base, xs, ys));
                }
            };
            addLayer("", image);
            for (const auto& [name, layer] : layers)
                addLayer(name, *layer);
            ExrSinkStream stream(sink, path);
            {
                Imf::OutputFile file(stream, header);
                file.setFrameBuffer(fb);
                file.writePixels(image.height());
            }  // the destructor writes the line-offset table (errors kept by the sink)
        } catch (const Error&) {
            throw;
        } catch (const std::exception& e) {
            LUCENT_THROW(IoError, "cannot write EXR '", path, "': ", e.what());
        }
        if (sink.failed())
            throw IoError(sink.error());
    });
}

void writeExr(const ImageRgb& image, const std::string& path) {
    writeExrLayers(image, {}, path);
}

ImageRgb readExr(const std::string& path, const std::string& layer) {
    checkInputFile(path, "EXR file");
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        checkDecodedImage(path, int64_t(dw.max.x) - dw.min.x + 1, int64_t(dw.max.y) - dw.min.y + 1);
        const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
        ImageRgb out(w, h);
        Imf::FrameBuffer fb;
        const char* names[3] = {"R", "G", "B"};
        for (int c = 0; c < 3; ++c) {
            const std::string ch = layer.empty() ? names[c] : layer + "." + names[c];
            if (!file.header().channels().findChannel(ch))
                LUCENT_THROW(IoError, "EXR file '", path, "' has no channel '", ch, "'");
            char* base = reinterpret_cast<char*>(out.pixels().data()) + c * sizeof(float) -
                         (size_t(dw.min.x) + size_t(dw.min.y) * w) * sizeof(Rgb);
            fb.insert(ch, Imf::Slice(Imf::FLOAT, base, sizeof(Rgb), sizeof(Rgb) * size_t(w)));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return out;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        LUCENT_THROW(IoError, "cannot read EXR '", path, "': ", e.what());
    }
}

}  // namespace lucent
