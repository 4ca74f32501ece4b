// SPDX-License-Identifier: Apache-2.0
/// @file ViewTypes.cpp
#include "render/views/ViewTypes.h"

#include "core/Errors.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace voxhap::render {

namespace {

constexpr ViewKind kViewOrder[] = {ViewKind::Axial, ViewKind::Sagittal, ViewKind::Coronal, ViewKind::ThreeD};

std::string_view trim(std::string_view s)
{
    while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
    while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
    return s;
}

bool parseDouble(std::string_view s, double& out)
{
    s = trim(s);
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && end == s.data() + s.size() && std::isfinite(out);
}

} // namespace

WindowLevel windowLevel(WindowPreset p)
{
    switch (p) {
    case WindowPreset::Bone:
        return {1800.0, 400.0};
    case WindowPreset::SoftTissue:
        return {400.0, 40.0};
    case WindowPreset::Lung:
        return {1500.0, -600.0};
    }
    return {};
}

std::string_view viewName(ViewKind v)
{
    switch (v) {
    case ViewKind::Axial:
        return "axial";
    case ViewKind::Sagittal:
        return "sagittal";
    case ViewKind::Coronal:
        return "coronal";
    case ViewKind::ThreeD:
        return "3d";
    }
    return "?";
}

std::string_view blendModeName(BlendMode m)
{
    switch (m) {
    case BlendMode::Colour:
        return "colour";
    case BlendMode::Grey:
        return "grey";
    case BlendMode::Mip:
        return "mip";
    case BlendMode::Sum:
        return "sum";
    }
    return "?";
}

std::vector<ViewKind> parseViews(std::string_view text)
{
    std::vector<ViewKind> seen;
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t comma = std::min(text.find(',', start), text.size());
        const std::string_view name = trim(text.substr(start, comma - start));
        const auto* it =
            std::find_if(std::begin(kViewOrder), std::end(kViewOrder), [&](ViewKind v) { return viewName(v) == name; });
        if (it == std::end(kViewOrder)) {
            throw ValueError("unknown view '" + std::string(name) + "' (expected axial, sagittal, coronal, 3d)");
        }
        seen.push_back(*it);
        start = comma + 1;
    }
    std::vector<ViewKind> out;
    for (ViewKind v : kViewOrder) {
        if (std::find(seen.begin(), seen.end(), v) != seen.end()) out.push_back(v);
    }
    return out;
}

BlendMode parseBlendMode(std::string_view text)
{
    const std::string_view t = trim(text);
    if (t == "colour" || t == "color") return BlendMode::Colour;
    if (t == "grey" || t == "gray") return BlendMode::Grey;
    if (t == "mip") return BlendMode::Mip;
    if (t == "sum") return BlendMode::Sum;
    throw ValueError("unknown mode '" + std::string(t) + "' (expected colour, grey, mip, sum)");
}

bool namesCtPreset(std::string_view text)
{
    const std::string_view t = trim(text);
    return t == "bone" || t == "soft" || t == "soft-tissue" || t == "lung";
}

WindowLevel parseWindow(std::string_view text)
{
    const std::string_view t = trim(text);
    if (t == "bone") return windowLevel(WindowPreset::Bone);
    if (t == "soft" || t == "soft-tissue") return windowLevel(WindowPreset::SoftTissue);
    if (t == "lung") return windowLevel(WindowPreset::Lung);
    const std::size_t comma = t.find(',');
    WindowLevel w;
    if (comma == std::string_view::npos || !parseDouble(t.substr(0, comma), w.width) ||
        !parseDouble(t.substr(comma + 1), w.level) || !(w.width > 0.0)) {
        throw ValueError(
            "window '" + std::string(t) + "': expected bone, soft, lung or WIDTH,LEVEL with a positive width");
    }
    return w;
}

std::string sliceTitle(ViewKind v, const Vec3d& p)
{
    std::ostringstream os;
    os << std::fixed << std::setprecision(1) << viewName(v);
    switch (v) {
    case ViewKind::Axial:
        os << "  z " << p.z() << " mm";
        break;
    case ViewKind::Sagittal:
        os << "  x " << p.x() << " mm";
        break;
    case ViewKind::Coronal:
        os << "  y " << p.y() << " mm";
        break;
    case ViewKind::ThreeD:
        break;
    }
    return os.str();
}

} // namespace voxhap::render
