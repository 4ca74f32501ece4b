// SPDX-License-Identifier: Apache-2.0
/// @file ImageFile.cpp
#include "render/raster/ImageFile.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"

#include <OpenImageIO/imageio.h>

#include <vector>

namespace voxhap::render {

namespace fs = std::filesystem;

void writePng(const Image& img, const fs::path& file)
{
    if (img.empty()) throw IoError(file.string() + ": cannot write an empty image");
    writeAtomically(file, [&](const fs::path& tmp) {
        // The temporary name does not end in .png: name the format explicitly.
        auto out = OIIO::ImageOutput::create("png");
        if (!out) throw IoError("no PNG writer in OpenImageIO (" + OIIO::geterror() + ")");
        const OIIO::ImageSpec spec(img.width(), img.height(), 3, OIIO::TypeDesc::UINT8);
        if (!out->open(tmp.string(), spec) || !out->write_image(OIIO::TypeDesc::UINT8, img.data()) || !out->close()) {
            throw IoError(out->geterror());
        }
    });
}

Image readImage(const fs::path& file)
{
    auto in = OIIO::ImageInput::open(file.string());
    if (!in) throw IoError(file.string() + ": cannot read the image (" + OIIO::geterror() + ")");
    const OIIO::ImageSpec& spec = in->spec();
    const int channels = spec.nchannels;
    if (channels < 1) throw IoError(file.string() + ": no channels");
    std::vector<std::uint8_t> pixels(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(channels));
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, pixels.data())) {
        throw IoError(file.string() + ": cannot read the pixels (" + in->geterror() + ")");
    }
    Image img(spec.width, spec.height);
    for (int y = 0; y < spec.height; ++y) {
        for (int x = 0; x < spec.width; ++x) {
            const std::uint8_t* p =
                &pixels[(std::size_t(y) * std::size_t(spec.width) + std::size_t(x)) * std::size_t(channels)];
            img.at(x, y) = channels >= 3 ? Rgb{p[0], p[1], p[2]} : Rgb{p[0], p[0], p[0]};
        }
    }
    return img;
}

} // namespace voxhap::render
