// SPDX-License-Identifier: Apache-2.0
/// @file JsonFields.h
/// @brief Strict reading of one JSON object for the project's data files
/// (scenes, plans): unknown keys and wrong types are refused with one line
/// "origin: field.path: why" (architecture.md "Errors"). Files are read
/// through core/BoundedRead.h (regular files of at most 16 MiB), and every
/// nlohmann::json exception, not only a syntax error, becomes one line naming
/// the file.
#pragma once

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/Math.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>

namespace voxhap {

/// @brief Reads one JSON object, refusing unknown keys (checked when it goes out
/// of scope) and wrong types with "origin: field: why".
class JsonFields {
public:
    using Json = nlohmann::json;

    JsonFields(const Json& j, std::string origin, std::string path)
        : mJ(j), mOrigin(std::move(origin)), mPath(std::move(path))
    {
        if (!j.is_object()) fail("", "must be an object");
    }
    ~JsonFields() noexcept(false)
    {
        if (std::uncaught_exceptions()) return;
        for (const auto& [k, v] : mJ.items()) {
            if (!mSeen.count(k)) fail(k, "unknown field");
        }
    }
    /// @brief Parse @p text; any nlohmann::json exception becomes
    /// ValueError "origin: not valid JSON (why)".
    static Json parse(std::string_view text, const std::string& origin) { return parseJsonText(text, origin); }
    /// @brief Read and parse @p file (a regular file within the 16 MiB limit).
    /// @throw IoError from readBoundedFile(), ValueError from parse()
    static Json readFile(const std::filesystem::path& file, std::string_view what) { return readJsonFile(file, what); }
    /// @brief Run @p read (which walks a parsed document); an nlohmann::json
    /// exception that escapes it (a value of a type the walk did not expect)
    /// becomes ValueError "origin: why" on one line.
    template <typename Read> static auto guarded(const std::string& origin, Read&& read) -> decltype(read())
    {
        try {
            return read();
        } catch (const Json::exception& e) {
            std::string why = e.what();
            for (char& c : why) {
                if (c == '\n' || c == '\r') c = ' ';
            }
            throw ValueError(origin + ": " + why);
        }
    }
    [[noreturn]] void fail(const std::string& key, const std::string& why) const
    {
        throw ValueError(mOrigin + ": " + (mPath.empty() ? key : key.empty() ? mPath : mPath + "." + key) + ": " + why);
    }
    bool has(const std::string& k)
    {
        mSeen.insert(k);
        return mJ.contains(k) && !mJ.at(k).is_null();
    }
    const Json& raw(const std::string& k)
    {
        mSeen.insert(k);
        if (!mJ.contains(k)) fail(k, "missing");
        return mJ.at(k);
    }
    double number(const std::string& k, double def, bool positive = false)
    {
        if (!has(k)) return def;
        const Json& v = mJ.at(k);
        if (!v.is_number() || !std::isfinite(v.get<double>())) fail(k, "must be a finite number");
        const double x = v.get<double>();
        if (positive ? !(x > 0.0) : x < 0.0) fail(k, positive ? "must be positive" : "must not be negative");
        return x;
    }
    /// @brief A number within its physical range: [lo, hi], or (lo, hi] when
    /// @p openLow; refused as "origin: field: must be in [lo, hi] unit (got x)".
    /// The ranges are the documented ones (docs/scenes.md for scenes).
    double within(const std::string& k, double def, double lo, double hi, const char* unit, bool openLow = false)
    {
        if (!has(k)) return def;
        const Json& v = mJ.at(k);
        if (!v.is_number() || !std::isfinite(v.get<double>())) fail(k, "must be a finite number");
        const double x = v.get<double>();
        if ((openLow ? !(x > lo) : !(x >= lo)) || !(x <= hi)) {
            fail(k,
                std::string("must be in ") + (openLow ? "(" : "[") + shortNumber(lo) + ", " + shortNumber(hi) + "]" +
                    (*unit ? " " : "") + unit + " (got " + shortNumber(x) + ")");
        }
        return x;
    }
    std::optional<double> optWithin(const std::string& k, double lo, double hi, const char* unit, bool openLow = false)
    {
        if (!has(k)) return std::nullopt;
        return within(k, 0.0, lo, hi, unit, openLow);
    }
    std::optional<double> optNumber(const std::string& k, bool positive = false)
    {
        if (!has(k)) return std::nullopt;
        return number(k, 0.0, positive);
    }
    bool boolean(const std::string& k, bool def)
    {
        if (!has(k)) return def;
        if (!mJ.at(k).is_boolean()) fail(k, "must be true or false");
        return mJ.at(k).get<bool>();
    }
    std::string string(const std::string& k, const std::string& def)
    {
        if (!has(k)) return def;
        if (!mJ.at(k).is_string()) fail(k, "must be a string");
        return mJ.at(k).get<std::string>();
    }
    Vec3d vec3(const std::string& k)
    {
        const Json& v = raw(k);
        if (!v.is_array() || v.size() != 3) fail(k, "must be [x, y, z] in mm");
        Vec3d p;
        for (int i = 0; i < 3; ++i) {
            if (!v[std::size_t(i)].is_number()) fail(k, "must be [x, y, z] in mm");
            p[i] = v[std::size_t(i)].get<double>();
        }
        if (!p.allFinite()) fail(k, "must be finite");
        return p;
    }
    JsonFields sub(const std::string& k) { return JsonFields(raw(k), mOrigin, mPath.empty() ? k : mPath + "." + k); }
    /// A term: absent → off; true or an object → on; false → off.
    bool term(const std::string& k)
    {
        if (!has(k)) return false;
        const Json& v = mJ.at(k);
        if (v.is_boolean()) return v.get<bool>();
        if (!v.is_object()) fail(k, "must be true, false or an object of parameters");
        return true;
    }
    bool isObject(const std::string& k) { return has(k) && mJ.at(k).is_object(); }

private:
    static std::string shortNumber(double x)
    {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.6g", x);
        return buf;
    }
    const Json& mJ;
    std::string mOrigin, mPath;
    std::set<std::string> mSeen;
};

} // namespace voxhap
