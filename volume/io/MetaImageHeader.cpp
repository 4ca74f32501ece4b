// SPDX-License-Identifier: Apache-2.0
/// @file MetaImageHeader.cpp
/// @brief "Key = Value" MetaImage header parsing and data location; parsed
/// by hand, and therefore fuzzed (fuzz/FuzzMetaImageHeader.cpp).

#include "volume/io/MetaImageHeader.h"

#include "core/Errors.h"

#include <cmath>
#include <map>
#include <sstream>
#include <vector>

namespace voxhap::volume {

namespace {

std::string trim(std::string_view s)
{
    std::size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return std::string(s.substr(a, b - a));
}

std::vector<double> numbers(const std::string& text, std::size_t n, const std::string& file, const std::string& key)
{
    std::istringstream in(text);
    std::vector<double> v(n);
    for (auto& x : v) {
        if (!(in >> x) || !std::isfinite(x)) {
            throw IoError(
                file + ": " + key + ": expected " + std::to_string(n) + " finite numbers, got '" + text + "'");
        }
    }
    if (!(in >> std::ws).eof())
        throw IoError(file + ": " + key + ": expected " + std::to_string(n) + " numbers, got '" + text + "'");
    return v;
}

bool isTrue(const std::string& v) { return v == "True" || v == "true" || v == "TRUE" || v == "1"; }

} // namespace

MetaImageHeader parseMetaImageHeader(std::string_view text, const std::filesystem::path& path)
{
    const std::string file = path.string();
    std::map<std::string, std::string> f;
    MetaImageHeader h;
    const std::string start = trim(text.substr(0, 64));
    if (start.rfind("ObjectType", 0) != 0 && start.rfind("NDims", 0) != 0) {
        throw IoError(file + ": magic: not a MetaImage header (it must start with ObjectType or NDims)");
    }
    std::size_t pos = 0;
    bool ended = false;
    while (pos < text.size()) {
        const std::size_t eol = text.find('\n', pos);
        if (eol == std::string_view::npos) break; // the ElementDataFile line must end with a newline
        const std::string_view line = text.substr(pos, eol - pos);
        pos = eol + 1;
        const std::size_t eq = line.find('=');
        if (eq == std::string_view::npos) {
            if (trim(line).empty()) continue;
            throw IoError(file + ": header: malformed line '" + trim(line) + "' (expected Key = Value)");
        }
        const std::string key = trim(line.substr(0, eq));
        if (f.count(key)) throw IoError(file + ": " + key + ": given twice");
        f[key] = trim(line.substr(eq + 1));
        if (key == "ElementDataFile") { // always the last field: the data follows
            ended = true;
            h.dataOffset = pos;
            break;
        }
    }
    if (!ended) throw IoError(file + ": ElementDataFile: missing (truncated header?)");
    const auto need = [&](const std::string& key) -> const std::string& {
        const auto it = f.find(key);
        if (it == f.end()) throw IoError(file + ": " + key + ": missing");
        return it->second;
    };
    if (f.count("ObjectType") && f["ObjectType"] != "Image")
        throw IoError(file + ": ObjectType: '" + f["ObjectType"] + "' (Image expected)");
    if (need("NDims") != "3") throw IoError(file + ": NDims: " + f["NDims"] + " (only 3D volumes are read)");
    if (f.count("ElementNumberOfChannels") && f["ElementNumberOfChannels"] != "1") {
        throw IoError(file + ": ElementNumberOfChannels: " + f["ElementNumberOfChannels"] + " (one channel expected)");
    }
    const auto dims = numbers(need("DimSize"), 3, file, "DimSize");
    for (int a = 0; a < 3; ++a) {
        if (dims[a] < 1 || dims[a] > (1 << 24) || dims[a] != std::floor(dims[a]))
            throw IoError(file + ": DimSize: '" + f["DimSize"] + "' out of range");
        h.layout.dims[a] = int(dims[a]);
    }
    static const std::map<std::string, SampleType> kTypes{{"MET_CHAR", SampleType::Int8},
        {"MET_UCHAR", SampleType::UInt8}, {"MET_SHORT", SampleType::Int16}, {"MET_USHORT", SampleType::UInt16},
        {"MET_INT", SampleType::Int32}, {"MET_UINT", SampleType::UInt32}, {"MET_LONG", SampleType::Int32},
        {"MET_ULONG", SampleType::UInt32}, {"MET_FLOAT", SampleType::Float32}, {"MET_DOUBLE", SampleType::Float64}};
    const auto type = kTypes.find(need("ElementType"));
    if (type == kTypes.end())
        throw IoError(file + ": ElementType: '" + f["ElementType"] + "' is not a supported scalar type");
    h.layout.type = type->second;
    const std::string msb = f.count("BinaryDataByteOrderMSB") ? f["BinaryDataByteOrderMSB"]
        : f.count("ElementByteOrderMSB")                      ? f["ElementByteOrderMSB"]
                                                              : "False";
    h.layout.bigEndian = isTrue(msb);
    if (f.count("BinaryData") && !isTrue(f["BinaryData"]))
        throw IoError(file + ": BinaryData: ASCII data is not supported");
    h.compressed = f.count("CompressedData") && isTrue(f["CompressedData"]);

    const std::string spacingKey = f.count("ElementSpacing") ? "ElementSpacing" : "ElementSize";
    if (f.count(spacingKey)) {
        const auto s = numbers(f[spacingKey], 3, file, spacingKey);
        for (int a = 0; a < 3; ++a) {
            if (!(s[a] > 0))
                throw IoError(file + ": " + spacingKey + ": must be positive, got '" + f[spacingKey] + "'");
            h.geometry.spacing[a] = s[a];
        }
    }
    for (const char* key : {"Offset", "Origin", "Position"}) {
        if (f.count(key)) {
            const auto o = numbers(f[key], 3, file, key);
            h.geometry.origin = Vec3d(o[0], o[1], o[2]);
            break;
        }
    }
    for (const char* key : {"TransformMatrix", "Rotation", "Orientation"}) {
        if (f.count(key)) {
            // ITK's layout: numbers 3a..3a+2 are the direction of index axis a.
            const auto m = numbers(f[key], 9, file, key);
            for (int a = 0; a < 3; ++a) {
                const Vec3d axis(m[3 * a], m[3 * a + 1], m[3 * a + 2]);
                if (std::abs(axis.norm() - 1.0) > 1e-4)
                    throw IoError(file + ": " + key + ": axis " + std::to_string(a) + " is not a unit vector");
                h.geometry.direction.col(a) = axis.normalized();
            }
            break;
        }
    }
    try {
        makeTransform(h.geometry);
    } catch (const ValueError& e) {
        throw IoError(file + ": TransformMatrix: " + e.what());
    }

    const std::string data = f["ElementDataFile"];
    if (data == "LOCAL" || data == "Local" || data == "local") {
        h.dataFile = path;
    } else {
        if (data.find(' ') != std::string::npos || data.find('\t') != std::string::npos || data == "LIST") {
            throw IoError(file + ": ElementDataFile: '" + data + "': file lists and patterns are not supported");
        }
        // Only a file of the header's own folder: no absolute path, no folder, no "..".
        // (Where a symbolic link of that name leads is checked by loadMetaImage.)
        if (data.empty() || data == "." || data == ".." || data.find('/') != std::string::npos ||
            data.find('\\') != std::string::npos) {
            throw IoError(file + ": ElementDataFile: '" + data +
                "' must name a file in the header's own folder (no absolute path, no folder, no '..')");
        }
        h.dataFile = path.parent_path() / data;
        h.dataOffset = 0;
        if (f.count("HeaderSize")) {
            const auto skip = numbers(f["HeaderSize"], 1, file, "HeaderSize")[0];
            if (skip < 0 || skip != std::floor(skip))
                throw IoError(file + ": HeaderSize: only a non-negative byte count is supported");
            h.dataOffset = std::uint64_t(skip);
        }
    }
    return h;
}

} // namespace voxhap::volume
