// SPDX-License-Identifier: Apache-2.0
/// @file NrrdHeader.cpp
/// @brief The attached NRRD header, parsed by hand (Debian has no maintained
/// NRRD library outside ITK/VTK, which the volume library must not pull in),
/// and therefore fuzzed (fuzz/FuzzNrrdHeader.cpp).

#include "volume/io/NrrdHeader.h"

#include "core/Errors.h"

#include <cctype>
#include <cmath>
#include <map>
#include <sstream>

namespace voxhap::volume {

namespace {

std::string lower(std::string s)
{
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string trimmed(std::string_view s)
{
    std::size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return std::string(s.substr(a, b - a));
}

/// "(a,b,c)" → vector; "none" is refused (every axis must be spatial).
Vec3d parseVector(const std::string& text, const std::string& file, const std::string& field)
{
    double v[3];
    char open = 0, c1 = 0, c2 = 0, close = 0;
    std::istringstream in(text);
    if (!(in >> open >> v[0] >> c1 >> v[1] >> c2 >> v[2] >> close) || open != '(' || c1 != ',' || c2 != ',' ||
        close != ')' || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
        throw IoError(file + ": " + field + ": expected (x,y,z) with finite numbers, got '" + text + "'");
    }
    return Vec3d(v[0], v[1], v[2]);
}

SampleType parseType(const std::string& t, const std::string& file)
{
    static const std::map<std::string, SampleType> kTypes{
        {"signed char", SampleType::Int8},
        {"int8", SampleType::Int8},
        {"int8_t", SampleType::Int8},
        {"uchar", SampleType::UInt8},
        {"unsigned char", SampleType::UInt8},
        {"uint8", SampleType::UInt8},
        {"uint8_t", SampleType::UInt8},
        {"short", SampleType::Int16},
        {"short int", SampleType::Int16},
        {"signed short", SampleType::Int16},
        {"signed short int", SampleType::Int16},
        {"int16", SampleType::Int16},
        {"int16_t", SampleType::Int16},
        {"ushort", SampleType::UInt16},
        {"unsigned short", SampleType::UInt16},
        {"unsigned short int", SampleType::UInt16},
        {"uint16", SampleType::UInt16},
        {"uint16_t", SampleType::UInt16},
        {"int", SampleType::Int32},
        {"signed int", SampleType::Int32},
        {"int32", SampleType::Int32},
        {"int32_t", SampleType::Int32},
        {"uint", SampleType::UInt32},
        {"unsigned int", SampleType::UInt32},
        {"uint32", SampleType::UInt32},
        {"uint32_t", SampleType::UInt32},
        {"float", SampleType::Float32},
        {"double", SampleType::Float64},
    };
    const auto it = kTypes.find(lower(t));
    if (it == kTypes.end()) throw IoError(file + ": type: '" + t + "' is not a supported sample type");
    return it->second;
}

} // namespace

NrrdHeader parseNrrdHeader(std::string_view text, const std::string& file)
{
    if (text.size() < 8 || text.substr(0, 7) != "NRRD000" || text[7] < '1' || text[7] > '5') {
        throw IoError(file + ": magic: not a NRRD file (expected NRRD0001 to NRRD0005)");
    }
    std::map<std::string, std::string> fields;
    NrrdHeader h;
    std::size_t pos = text.find('\n');
    bool ended = false;
    while (pos != std::string_view::npos && pos + 1 <= text.size()) {
        const std::size_t next = text.find('\n', pos + 1);
        if (next == std::string_view::npos) break;
        std::string_view line = text.substr(pos + 1, next - pos - 1);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        pos = next;
        if (line.empty()) {
            ended = true;
            h.dataOffset = next + 1;
            break;
        }
        if (line.front() == '#') continue;
        const std::size_t kv = line.find(":=");
        if (kv != std::string_view::npos) {
            h.keyValues[trimmed(line.substr(0, kv))] = trimmed(line.substr(kv + 2));
            continue;
        }
        const std::size_t colon = line.find(": ");
        if (colon == std::string_view::npos)
            throw IoError(file + ": header: malformed line '" + std::string(line) + "'");
        const std::string key = lower(trimmed(line.substr(0, colon)));
        if (fields.count(key)) throw IoError(file + ": " + key + ": given twice");
        fields[key] = trimmed(line.substr(colon + 2));
    }
    if (!ended) throw IoError(file + ": header: no blank line ends the header (truncated file?)");

    const auto need = [&](const std::string& key) -> const std::string& {
        const auto it = fields.find(key);
        if (it == fields.end()) throw IoError(file + ": " + key + ": missing");
        return it->second;
    };
    if (fields.count("data file") || fields.count("datafile")) {
        throw IoError(file + ": data file: detached data (.nhdr) is not supported; save as a single .nrrd");
    }
    for (const char* skip : {"line skip", "lineskip", "byte skip", "byteskip"}) {
        if (fields.count(skip) && fields[skip] != "0") throw IoError(file + ": " + skip + ": only 0 is supported");
    }
    h.layout.type = parseType(need("type"), file);
    if (need("dimension") != "3")
        throw IoError(file + ": dimension: " + fields["dimension"] + " (only 3D volumes are read)");
    {
        std::istringstream in(need("sizes"));
        long long s[3];
        if (!(in >> s[0] >> s[1] >> s[2]) || !(in >> std::ws).eof()) {
            throw IoError(file + ": sizes: expected three whole numbers, got '" + fields["sizes"] + "'");
        }
        for (int a = 0; a < 3; ++a) {
            if (s[a] < 1 || s[a] > (1 << 24)) throw IoError(file + ": sizes: '" + fields["sizes"] + "' out of range");
            h.layout.dims[a] = int(s[a]);
        }
    }
    const std::string enc = lower(need("encoding"));
    if (enc == "gzip" || enc == "gz")
        h.gzip = true;
    else if (enc != "raw")
        throw IoError(file + ": encoding: '" + enc + "' is not supported (raw or gzip)");
    if (sampleBytes(h.layout.type) > 1) {
        const std::string e = lower(need("endian"));
        if (e != "little" && e != "big") throw IoError(file + ": endian: '" + e + "' (little or big)");
        h.layout.bigEndian = e == "big";
    }
    const std::string space = lower(need("space"));
    Vec3d flip(1, 1, 1); // file space → LPS
    if (space == "right-anterior-superior" || space == "ras")
        flip = Vec3d(-1, -1, 1);
    else if (space == "left-anterior-superior" || space == "las")
        flip = Vec3d(1, -1, 1);
    else if (space != "left-posterior-superior" && space != "lps") {
        throw IoError(file + ": space: '" + space + "' (LPS, RAS or LAS expected)");
    }
    {
        const std::string& dirs = need("space directions");
        std::istringstream in(dirs);
        for (int a = 0; a < 3; ++a) {
            std::string tok;
            if (!(in >> tok)) throw IoError(file + ": space directions: expected three vectors, got '" + dirs + "'");
            const Vec3d d = parseVector(tok, file, "space directions").cwiseProduct(flip);
            h.geometry.spacing[a] = d.norm();
            if (!(h.geometry.spacing[a] > 0))
                throw IoError(file + ": space directions: axis " + std::to_string(a) + " has zero length");
            h.geometry.direction.col(a) = d / h.geometry.spacing[a];
        }
    }
    if (fields.count("space origin"))
        h.geometry.origin = parseVector(fields["space origin"], file, "space origin").cwiseProduct(flip);
    try {
        makeTransform(h.geometry); // same checks as every Volume: unit, non-degenerate directions
    } catch (const ValueError& e) {
        const bool origin = std::string_view(e.what()).find("origin") != std::string_view::npos;
        throw IoError(file + (origin ? ": space origin: " : ": space directions: ") + e.what());
    }
    return h;
}

} // namespace voxhap::volume
