// SPDX-License-Identifier: Apache-2.0
/// @file TissueTable.cpp
/// @brief Parsing, unit conversion and validation of the tissue table.

#include "volume/TissueTable.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/JsonFields.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace voxhap::volume {

extern const char* const kBuiltinTissueTableJson; // generated from data/tissues.json

namespace {

using Json = nlohmann::json;

/// The kinds of quantity the table holds, each with the units it accepts and
/// the factor that converts them to the canonical unit (first in the list).
enum class Dimension {
    Hounsfield,
    RelaxationMs,
    Length,
    Force,
    Stiffness,
    DampingDensity,
    FoundationModulus
};

struct UnitFactor {
    std::string_view unit;
    double factor;
};

const std::vector<UnitFactor>& unitsOf(Dimension d)
{
    static const std::map<Dimension, std::vector<UnitFactor>> kUnits{
        {Dimension::Hounsfield, {{"HU", 1.0}}},
        {Dimension::RelaxationMs, {{"ms", 1.0}, {"s", 1000.0}}},
        {Dimension::Length, {{"mm", 1.0}, {"cm", 10.0}, {"m", 1000.0}}},
        {Dimension::Force, {{"N", 1.0}, {"mN", 1e-3}}},
        {Dimension::Stiffness, {{"N/mm", 1.0}, {"N/m", 1e-3}}},
        // N·s/m² → N·s/mm²: 1 m² = 1e6 mm².
        {Dimension::DampingDensity, {{"N*s/mm^2", 1.0}, {"N*s/m^2", 1e-6}}},
        // A Winkler modulus is force per length of shaft per mm of deflection: N/mm², = MPa.
        {Dimension::FoundationModulus, {{"N/mm^2", 1.0}, {"MPa", 1.0}, {"kPa", 1e-3}}},
    };
    return kUnits.at(d);
}

/// The largest physical value of each kind, in its canonical unit (docs/scenes.md,
/// "The tissue table"): beyond it a value is a typo or an attack, not a tissue.
/// T1 of pure water at 3 T is about 4 s; no needle is longer than a metre; no
/// haptic device renders 100 N; the stiffest and most viscous layers measured
/// (physics.md §4, §5.4) are orders of magnitude below the others.
double maxCanonical(Dimension d)
{
    switch (d) {
    case Dimension::RelaxationMs:
        return 10000.0; // ms
    case Dimension::Length:
        return 1000.0; // mm
    case Dimension::Force:
        return 100.0; // N
    case Dimension::Stiffness:
        return 100.0; // N/mm
    case Dimension::DampingDensity:
        return 1.0; // N·s/mm² (1e6 N·s/m²)
    case Dimension::FoundationModulus:
        return 1e4; // N/mm²: 10 GPa, cortical bone's Young's modulus order
    case Dimension::Hounsfield:
        return 32767.0; // HU: the largest 16-bit signed CT number
    }
    return 0.0;
}

std::string unitList(Dimension d)
{
    std::string out;
    for (const auto& u : unitsOf(d)) {
        if (!out.empty()) out += ", ";
        out += u.unit;
    }
    return out;
}

/// One optional mechanical field of a Tissue.
struct MechanicalField {
    std::string_view key;
    Dimension dimension;
    std::optional<Quantity> Tissue::*member;
};

const std::vector<MechanicalField>& mechanicalFields()
{
    static const std::vector<MechanicalField> kFields{
        {"thickness", Dimension::Length, &Tissue::thickness},
        {"puncture_force", Dimension::Force, &Tissue::punctureForce},
        {"cutting_force", Dimension::Force, &Tissue::cuttingForce},
        {"elasticity", Dimension::Stiffness, &Tissue::elasticity},
        {"friction_viscous", Dimension::DampingDensity, &Tissue::frictionViscous},
        {"friction_coulomb", Dimension::Force, &Tissue::frictionCoulomb},
        {"damping", Dimension::DampingDensity, &Tissue::damping},
        {"foundation_modulus", Dimension::FoundationModulus, &Tissue::foundationModulus},
    };
    return kFields;
}

const std::set<std::string, std::less<>> kTopKeys{"schema", "description", "tissues"};
const std::set<std::string, std::less<>> kTissueKeys{"id", "name", "colour", "critical", "rigid", "description", "hu",
    "t1_1.5T", "t1_3T", "thickness", "puncture_force", "cutting_force", "elasticity", "friction_viscous",
    "friction_coulomb", "damping", "foundation_modulus"};
const std::set<std::string, std::less<>> kQuantityKeys{"value", "unit", "source", "chosen", "note"};
const std::set<std::string, std::less<>> kRangeKeys{"min", "typical", "max", "unit", "source", "chosen", "note"};

/// Builds messages of the form "<file>: tissue 'fat' (id 2): field 'thickness': <what>".
class Context {
public:
    explicit Context(std::string origin) : mOrigin(std::move(origin)) { }
    void setTissue(std::string label) { mTissue = std::move(label); }
    [[noreturn]] void fail(const std::string& field, const std::string& what) const
    {
        std::ostringstream os;
        os << mOrigin << ": ";
        if (!mTissue.empty()) os << mTissue << ": ";
        if (!field.empty()) os << "field '" << field << "': ";
        os << what;
        throw ValueError(os.str());
    }

private:
    std::string mOrigin;
    std::string mTissue;
};

void rejectUnknownKeys(
    const Json& obj, const std::set<std::string, std::less<>>& allowed, const Context& ctx, const std::string& field)
{
    for (const auto& [key, value] : obj.items()) {
        if (!allowed.count(key)) ctx.fail(field, "unknown key '" + key + "'");
    }
}

double finiteNumber(const Json& obj, const char* key, const Context& ctx, const std::string& field)
{
    if (!obj.contains(key)) ctx.fail(field, std::string("missing '") + key + "'");
    const Json& v = obj.at(key);
    if (!v.is_number()) ctx.fail(field, std::string("'") + key + "' is not a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) ctx.fail(field, std::string("'") + key + "' is not finite");
    return d;
}

/// Common part of quantities and ranges: unit (of the right kind) and source.
double unitFactor(const Json& obj, Dimension dim, const Context& ctx, const std::string& field)
{
    if (!obj.contains("unit")) ctx.fail(field, "missing 'unit' (expected one of: " + unitList(dim) + ")");
    if (!obj.at("unit").is_string()) ctx.fail(field, "'unit' is not a string");
    const auto unit = obj.at("unit").get<std::string>();
    for (const auto& u : unitsOf(dim)) {
        if (u.unit == unit) return u.factor;
    }
    ctx.fail(field, "unit '" + unit + "' is not one of: " + unitList(dim));
}

std::string sourceOf(const Json& obj, const Context& ctx, const std::string& field)
{
    if (!obj.contains("source") || !obj.at("source").is_string() || obj.at("source").get<std::string>().empty()) {
        ctx.fail(field, "missing 'source'");
    }
    return obj.at("source").get<std::string>();
}

bool chosenOf(const Json& obj, const Context& ctx, const std::string& field)
{
    if (!obj.contains("chosen")) return false;
    if (!obj.at("chosen").is_boolean()) ctx.fail(field, "'chosen' is not true or false");
    return obj.at("chosen").get<bool>();
}

Quantity parseQuantity(const Json& obj, Dimension dim, const Context& ctx, const std::string& field)
{
    if (!obj.is_object()) ctx.fail(field, "expected an object {\"value\", \"unit\", \"source\"}");
    rejectUnknownKeys(obj, kQuantityKeys, ctx, field);
    Quantity q;
    const double raw = finiteNumber(obj, "value", ctx, field);
    if (raw < 0.0) ctx.fail(field, "negative value " + std::to_string(raw));
    q.value = raw * unitFactor(obj, dim, ctx, field);
    if (q.value > maxCanonical(dim)) {
        ctx.fail(field,
            "value " + std::to_string(raw) + " is beyond the physical range (at most " +
                std::to_string(maxCanonical(dim)) + " " + std::string(unitsOf(dim).front().unit) + ")");
    }
    q.source = sourceOf(obj, ctx, field);
    q.chosen = chosenOf(obj, ctx, field);
    return q;
}

void parseHu(const Json& obj, Tissue& t, const Context& ctx)
{
    const std::string field = "hu";
    if (!obj.is_object()) ctx.fail(field, "expected an object {\"min\", \"typical\", \"max\", \"unit\", \"source\"}");
    rejectUnknownKeys(obj, kRangeKeys, ctx, field);
    unitFactor(obj, Dimension::Hounsfield, ctx, field);
    // CT numbers are negative for air, lung and fat: no sign check, only order.
    t.huMin = finiteNumber(obj, "min", ctx, field);
    t.huTypical = finiteNumber(obj, "typical", ctx, field);
    t.huMax = finiteNumber(obj, "max", ctx, field);
    if (!(t.huMin <= t.huTypical && t.huTypical <= t.huMax)) {
        ctx.fail(field, "expected min <= typical <= max");
    }
    // CT numbers are stored as 16-bit signed values (some scanners write -3024 outside
    // the field of view): beyond that range a bound is a typo.
    if (t.huMin < -32768.0 || t.huMax > maxCanonical(Dimension::Hounsfield)) {
        ctx.fail(field, "expected CT numbers within [-32768, 32767] HU");
    }
    t.huSource = sourceOf(obj, ctx, field);
}

std::array<std::uint8_t, 3> parseColour(const Json& v, const Context& ctx)
{
    if (!v.is_array() || v.size() != 3) ctx.fail("colour", "expected [r, g, b] with 0..255 each");
    std::array<std::uint8_t, 3> c{};
    for (int i = 0; i < 3; ++i) {
        if (!v[i].is_number_integer() || v[i].get<long long>() < 0 || v[i].get<long long>() > 255) {
            ctx.fail("colour", "expected [r, g, b] with 0..255 each");
        }
        c[i] = static_cast<std::uint8_t>(v[i].get<int>());
    }
    return c;
}

Tissue parseTissue(const Json& obj, std::size_t index, Context& ctx)
{
    ctx.setTissue("tissue #" + std::to_string(index));
    if (!obj.is_object()) ctx.fail("", "expected an object");
    Tissue t;
    if (!obj.contains("name") || !obj.at("name").is_string() || obj.at("name").get<std::string>().empty()) {
        ctx.fail("name", "missing or not a string");
    }
    t.name = obj.at("name").get<std::string>();
    ctx.setTissue("tissue '" + t.name + "'");
    if (!obj.contains("id") || !obj.at("id").is_number_integer()) ctx.fail("id", "missing or not an integer");
    const long long id = obj.at("id").get<long long>();
    if (id < 0 || id > 32767) ctx.fail("id", "must be in 0..32767");
    t.id = static_cast<int>(id);
    ctx.setTissue("tissue '" + t.name + "' (id " + std::to_string(t.id) + ")");
    rejectUnknownKeys(obj, kTissueKeys, ctx, "");

    if (!obj.contains("colour")) ctx.fail("colour", "missing");
    t.colour = parseColour(obj.at("colour"), ctx);
    if (obj.contains("critical")) {
        if (!obj.at("critical").is_boolean()) ctx.fail("critical", "not true or false");
        t.critical = obj.at("critical").get<bool>();
    }
    if (obj.contains("rigid")) {
        if (!obj.at("rigid").is_boolean()) ctx.fail("rigid", "not true or false");
        t.rigid = obj.at("rigid").get<bool>();
    }
    if (obj.contains("description")) {
        if (!obj.at("description").is_string()) ctx.fail("description", "not a string");
        t.description = obj.at("description").get<std::string>();
    }
    if (!obj.contains("hu")) ctx.fail("hu", "missing");
    parseHu(obj.at("hu"), t, ctx);
    for (const char* key : {"t1_1.5T", "t1_3T"}) {
        if (!obj.contains(key)) ctx.fail(key, "missing");
    }
    t.t1At1p5T = parseQuantity(obj.at("t1_1.5T"), Dimension::RelaxationMs, ctx, "t1_1.5T");
    t.t1At3T = parseQuantity(obj.at("t1_3T"), Dimension::RelaxationMs, ctx, "t1_3T");
    for (const auto& f : mechanicalFields()) {
        const std::string key(f.key);
        if (obj.contains(key)) t.*(f.member) = parseQuantity(obj.at(key), f.dimension, ctx, key);
    }
    return t;
}

std::size_t lineOf(std::string_view text, std::size_t byte)
{
    byte = std::min(byte, text.size());
    return 1 + std::size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(byte), '\n'));
}

/// "<file>:<line>: tissue '<name>': value <literal> is not finite", from nlohmann's
/// "number overflow parsing '<literal>'" message and the text around the literal.
std::string describeOverflow(std::string_view text, const std::string& what, const std::string& origin)
{
    const auto open = what.find('\''), close = what.rfind('\'');
    if (open == std::string::npos || close <= open) return origin + ": a number is not finite (" + what + ")";
    const std::string literal = what.substr(open + 1, close - open - 1);
    const std::size_t at = text.find(literal);
    if (at == std::string_view::npos) return origin + ": value " + literal + " is not finite";
    std::string out = origin + ":" + std::to_string(lineOf(text, at)) + ": ";
    // The entry is named by the last "name" key before the literal.
    const std::size_t key = text.rfind("\"name\"", at);
    if (key != std::string_view::npos) {
        const std::size_t q1 = text.find('"', text.find(':', key));
        const std::size_t q2 = q1 == std::string_view::npos ? q1 : text.find('"', q1 + 1);
        if (q2 != std::string_view::npos) out += "tissue '" + std::string(text.substr(q1 + 1, q2 - q1 - 1)) + "': ";
    }
    return out + "value " + literal + " is not finite";
}

} // namespace

TissueTable TissueTable::parse(std::string_view text, const std::string& origin)
{
    Json root;
    try {
        root = Json::parse(text);
    } catch (const Json::parse_error& e) {
        throw IoError(origin + ":" + std::to_string(lineOf(text, e.byte)) + ": not valid JSON");
    } catch (const Json::out_of_range& e) {
        // A literal beyond double range (e.g. 1e999) is the one way a non-finite
        // number reaches us; nlohmann reports it without a position, so find it.
        throw ValueError(describeOverflow(text, e.what(), origin));
    } catch (const Json::exception& e) { // any other: one line naming the file
        throw IoError(origin + ": not valid JSON (" + std::string(e.what()) + ")");
    }
    // A value of a type the walk below did not expect, likewise.
    return JsonFields::guarded(origin, [&] {
        Context ctx(origin);
        if (!root.is_object()) ctx.fail("", "expected a JSON object at the top level");
        rejectUnknownKeys(root, kTopKeys, ctx, "");
        if (!root.contains("tissues") || !root.at("tissues").is_array() || root.at("tissues").empty()) {
            ctx.fail("tissues", "missing or not a non-empty array");
        }

        TissueTable table;
        table.mOrigin = origin;
        std::set<std::string, std::less<>> names;
        std::size_t index = 0;
        for (const auto& entry : root.at("tissues")) {
            Tissue t = parseTissue(entry, index++, ctx);
            if (table.find(t.id)) ctx.fail("id", "duplicate id " + std::to_string(t.id));
            if (!names.insert(t.name).second) ctx.fail("name", "duplicate name '" + t.name + "'");
            table.mMaxId = std::max(table.mMaxId, t.id);
            table.mIndexById.resize(static_cast<std::size_t>(table.mMaxId) + 1, -1);
            table.mIndexById[static_cast<std::size_t>(t.id)] = static_cast<int>(table.mTissues.size());
            table.mTissues.push_back(std::move(t));
        }
        const Tissue* air = table.find(0);
        if (!air || air->name != "air") {
            Context(origin).fail("tissues", "id 0 must be 'air', the background of every grid");
        }
        return table;
    });
}

TissueTable TissueTable::load(const std::filesystem::path& file)
{
    // A regular file within the size limit: not a FIFO, /dev/zero or a huge file.
    return parse(readBoundedFile(file, "tissue table"), file.string());
}

const TissueTable& TissueTable::builtin()
{
    static const TissueTable kTable = parse(kBuiltinTissueTableJson, "builtin data/tissues.json");
    return kTable;
}

const Tissue* TissueTable::find(int id) const
{
    if (id < 0 || id >= static_cast<int>(mIndexById.size())) return nullptr;
    const int i = mIndexById[static_cast<std::size_t>(id)];
    return i < 0 ? nullptr : &mTissues[static_cast<std::size_t>(i)];
}

const Tissue* TissueTable::find(std::string_view name) const
{
    for (const auto& t : mTissues) {
        if (t.name == name) return &t;
    }
    return nullptr;
}

const Tissue& TissueTable::at(int id) const
{
    if (const Tissue* t = find(id)) return *t;
    throw ValueError(mOrigin + ": no tissue with id " + std::to_string(id));
}

const Tissue& TissueTable::at(std::string_view name) const
{
    if (const Tissue* t = find(name)) return *t;
    std::string known;
    for (const auto& t : mTissues) known += (known.empty() ? "" : ", ") + t.name;
    throw ValueError(mOrigin + ": no tissue named '" + std::string(name) + "' (known: " + known + ")");
}

} // namespace voxhap::volume
