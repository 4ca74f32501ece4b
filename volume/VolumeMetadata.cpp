// SPDX-License-Identifier: Apache-2.0
/// @file VolumeMetadata.cpp
/// @brief The typed facts' names and text forms, and the reading of files
/// written before the facts were typed.

#include "volume/VolumeMetadata.h"

#include "core/Errors.h"

#include <nlohmann/json.hpp>

#include <array>
#include <charconv>
#include <cmath>
#include <regex>

namespace voxhap::volume {

namespace {

using Json = nlohmann::json;

constexpr std::array kFactSources{FactSource::Unknown, FactSource::Header, FactSource::Sidecar, FactSource::User,
    FactSource::Data, FactSource::Assumed, FactSource::Generator};

constexpr std::array kWeightings{MrWeightingKind::T1Map, MrWeightingKind::T1Weighted, MrWeightingKind::PdWeighted,
    MrWeightingKind::T2Weighted, MrWeightingKind::T2StarWeighted, MrWeightingKind::Flair, MrWeightingKind::Stir,
    MrWeightingKind::SteadyState, MrWeightingKind::Diffusion, MrWeightingKind::FieldMap, MrWeightingKind::Phase,
    MrWeightingKind::Perfusion, MrWeightingKind::Functional, MrWeightingKind::Susceptibility,
    MrWeightingKind::Angiography, MrWeightingKind::Localizer, MrWeightingKind::OtherMap, MrWeightingKind::Derived,
    MrWeightingKind::Unknown};

/// The inverse of a name function over every value of an enum.
template <class E, std::size_t N, class Name>
std::optional<E> byName(const std::array<E, N>& all, Name name, std::string_view text)
{
    for (E e : all) {
        if (name(e) == text) return e;
    }
    return std::nullopt;
}

/// Shortest text that reads back as the same double.
std::string roundTrip(double v)
{
    std::array<char, 32> buf{};
    const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    return std::string(buf.data(), r.ptr);
}

std::string badValue(const std::string& where, std::string_view name, const std::string& text, const char* expected)
{
    return where + ": metadata '" + std::string(name) + "': '" + text + "' is not " + expected;
}

double parseNumber(const std::string& text, const std::string& where, std::string_view name)
{
    double v = 0.0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size() || !std::isfinite(v))
        throw ValueError(badValue(where, name, text, "a finite number"));
    return v;
}

int parseCount(const std::string& text, const std::string& where, std::string_view name)
{
    int v = 0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc() || r.ptr != text.data() + text.size() || v < 1)
        throw ValueError(badValue(where, name, text, "a whole number from 1"));
    return v;
}

template <class E>
E parseEnum(
    std::optional<E> e, const std::string& text, const std::string& where, std::string_view name, const char* expected)
{
    if (!e) throw ValueError(badValue(where, name, text, expected));
    return *e;
}

Json toJson(const Vec3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

Vec3d vecFrom(const Json& j, const std::string& where, std::string_view name, const std::string& what)
{
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number()) {
        throw ValueError(where + ": metadata '" + std::string(name) + "': '" + what + "' is not [x, y, z]");
    }
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

Json parseJson(const std::string& text, const std::string& where, std::string_view name)
{
    Json doc = Json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (doc.is_discarded()) throw ValueError(where + ": metadata '" + std::string(name) + "' is not valid JSON");
    return doc;
}

std::string layersText(const PhantomLayers& p)
{
    Json jl = Json::array();
    for (const auto& l : p.layers)
        jl.push_back({{"tissue", l.name}, {"id", l.tissue}, {"start_mm", l.startMm}, {"end_mm", l.endMm}});
    return Json{{"entry", toJson(p.entry)}, {"direction", toJson(p.direction)}, {"layers", jl}}.dump();
}

PhantomLayers parseLayers(const std::string& text, const std::string& where, std::string_view name)
{
    const Json doc = parseJson(text, where, name);
    if (!doc.is_object() || !doc.contains("layers") || !doc["layers"].is_array())
        throw ValueError(where + ": metadata '" + std::string(name) + "' has no 'layers' array");
    PhantomLayers out;
    out.entry = vecFrom(doc.value("entry", Json()), where, name, "entry");
    out.direction = vecFrom(doc.value("direction", Json()), where, name, "direction");
    for (const auto& l : doc["layers"]) {
        LayerSpan s;
        try {
            s.name = l.at("tissue").get<std::string>();
            s.tissue = l.at("id").get<int>();
            s.startMm = l.at("start_mm").get<double>();
            s.endMm = l.at("end_mm").get<double>();
        } catch (const Json::exception&) {
            throw ValueError(
                where + ": metadata '" + std::string(name) + "': a layer lacks tissue, id, start_mm or end_mm");
        }
        out.layers.push_back(std::move(s));
    }
    return out;
}

std::string landmarksText(const std::map<std::string, Vec3d>& marks)
{
    Json j = Json::object();
    for (const auto& [n, p] : marks) j[n] = toJson(p);
    return j.dump();
}

std::map<std::string, Vec3d> parseLandmarks(const std::string& text, const std::string& where, std::string_view name)
{
    const Json doc = parseJson(text, where, name);
    if (!doc.is_object()) throw ValueError(where + ": metadata '" + std::string(name) + "' is not a JSON object");
    std::map<std::string, Vec3d> out;
    for (const auto& [n, p] : doc.items()) out[n] = vecFrom(p, where, name, n);
    return out;
}

/// What the reason text of a file written before modality_source was typed says.
FactSource legacyModalitySource(const std::string& why)
{
    if (why.rfind("declared by the file", 0) == 0) return FactSource::Header;
    if (why.rfind("declared by the user", 0) == 0) return FactSource::User;
    if (why.find("BIDS sidecar") != std::string::npos) return FactSource::Sidecar;
    if (why.rfind("inferred from the data", 0) == 0) return FactSource::Data;
    return FactSource::Unknown;
}

/// "2 of 13 (b=1000)", as files written before the choice was typed hold it.
std::optional<VolumeChoice> legacyVolumeChoice(const std::string& text)
{
    static const std::regex form(R"(^([0-9]+) of ([0-9]+) \((.*)\)$)");
    std::smatch m;
    if (!std::regex_match(text, m, form)) return std::nullopt;
    try {
        return VolumeChoice{std::stoi(m[1]), std::stoi(m[2]), m[3]};
    } catch (const std::exception&) {
        return std::nullopt;
    }
}

} // namespace

std::string_view fieldStrengthName(FieldStrength f) { return f == FieldStrength::T3 ? "3T" : "1.5T"; }

std::optional<FieldStrength> parseFieldStrength(std::string_view name)
{
    return byName(std::array{FieldStrength::T1_5, FieldStrength::T3}, fieldStrengthName, name);
}

std::optional<FieldStrength> fieldStrengthOfTesla(double tesla)
{
    if (std::abs(tesla - 1.5) <= kFieldStrengthToleranceT) return FieldStrength::T1_5;
    if (std::abs(tesla - 3.0) <= kFieldStrengthToleranceT) return FieldStrength::T3;
    return std::nullopt;
}

void recordFieldStrength(VolumeMetadata& md, std::optional<double> tesla, FactSource from, FieldStrength assumed)
{
    if (tesla && !std::isfinite(*tesla)) tesla.reset(); // says nothing
    md.fieldStrengthTesla = tesla;
    md.fieldStrength = tesla ? fieldStrengthOfTesla(*tesla) : assumed;
    md.fieldStrengthSource = tesla ? from : FactSource::Assumed;
}

std::string_view factSourceName(FactSource s)
{
    switch (s) {
    case FactSource::Header:
        return "header";
    case FactSource::Sidecar:
        return "sidecar";
    case FactSource::User:
        return "user";
    case FactSource::Data:
        return "data";
    case FactSource::Assumed:
        return "assumed";
    case FactSource::Generator:
        return "generator";
    case FactSource::Unknown:
        break;
    }
    return "unknown";
}

std::optional<FactSource> parseFactSource(std::string_view name) { return byName(kFactSources, factSourceName, name); }

std::string_view mrWeightingName(MrWeightingKind k)
{
    switch (k) {
    case MrWeightingKind::T1Map:
        return "T1 map";
    case MrWeightingKind::T1Weighted:
        return "T1-weighted";
    case MrWeightingKind::PdWeighted:
        return "PD-weighted";
    case MrWeightingKind::T2Weighted:
        return "T2-weighted";
    case MrWeightingKind::T2StarWeighted:
        return "T2*-weighted";
    case MrWeightingKind::Flair:
        return "FLAIR";
    case MrWeightingKind::Stir:
        return "STIR";
    case MrWeightingKind::SteadyState:
        return "steady state";
    case MrWeightingKind::Diffusion:
        return "diffusion";
    case MrWeightingKind::FieldMap:
        return "field map";
    case MrWeightingKind::Phase:
        return "phase";
    case MrWeightingKind::Perfusion:
        return "perfusion";
    case MrWeightingKind::Functional:
        return "functional";
    case MrWeightingKind::Susceptibility:
        return "susceptibility";
    case MrWeightingKind::Angiography:
        return "angiography";
    case MrWeightingKind::Localizer:
        return "localizer";
    case MrWeightingKind::OtherMap:
        return "quantitative map";
    case MrWeightingKind::Derived:
        return "derived";
    case MrWeightingKind::Unknown:
        return "unknown";
    }
    return "unknown";
}

std::optional<MrWeightingKind> parseMrWeighting(std::string_view name)
{
    return byName(kWeightings, mrWeightingName, name);
}

std::string_view t1KindName(T1Kind k) { return k == T1Kind::Map ? "T1 map" : "T1-weighted, normalised per scan"; }

std::optional<T1Kind> parseT1Kind(std::string_view name)
{
    return byName(std::array{T1Kind::Map, T1Kind::NormalisedWeighted}, t1KindName, name);
}

std::string volumeChoiceText(const VolumeChoice& c)
{
    return std::to_string(c.index) + " of " + std::to_string(c.count) + (c.label.empty() ? "" : " (" + c.label + ")");
}

std::vector<std::pair<std::string, std::string>> metadataFacts(const VolumeMetadata& md)
{
    std::vector<std::pair<std::string, std::string>> out;
    const auto put = [&out](const char* name, std::string text) { out.emplace_back(name, std::move(text)); };
    if (!md.modality.empty()) put("modality", md.modality);
    if (md.modalitySource != FactSource::Unknown)
        put("modality_source", std::string(factSourceName(md.modalitySource)));
    if (!md.modalityReason.empty()) put("modality_reason", md.modalityReason);
    if (md.mrWeighting) put("mr_weighting", std::string(mrWeightingName(*md.mrWeighting)));
    if (md.t1Kind) put("t1_kind", std::string(t1KindName(*md.t1Kind)));
    if (md.fieldStrength) put("field_strength", std::string(fieldStrengthName(*md.fieldStrength)));
    if (md.fieldStrengthSource != FactSource::Unknown)
        put("field_strength_source", std::string(factSourceName(md.fieldStrengthSource)));
    if (md.fieldStrengthTesla) put("field_strength_tesla", roundTrip(*md.fieldStrengthTesla));
    if (md.bodyWidthMm) put("body_width_mm", roundTrip(*md.bodyWidthMm));
    if (!md.seriesUid.empty()) put("series_uid", md.seriesUid);
    if (md.volumeChoice) {
        put("volume", std::to_string(md.volumeChoice->index));
        put("volume_count", std::to_string(md.volumeChoice->count));
        put("volume_label", md.volumeChoice->label);
    }
    if (md.phantomLayers) put("layers", layersText(*md.phantomLayers));
    if (!md.landmarks.empty()) put("landmarks", landmarksText(md.landmarks));
    if (md.fusion) put("fusion", toJson(*md.fusion).dump());
    return out;
}

bool setMetadataFact(VolumeMetadata& md, std::string_view name, const std::string& text, const std::string& where)
{
    const auto choice = [&md]() -> VolumeChoice& {
        if (!md.volumeChoice) md.volumeChoice.emplace();
        return *md.volumeChoice;
    };
    if (name == "modality") {
        md.modality = text;
    } else if (name == "modality_source") {
        md.modalitySource = parseEnum(parseFactSource(text), text, where, name, "a source (header, sidecar, ...)");
    } else if (name == "modality_reason") {
        md.modalityReason = text;
    } else if (name == "mr_weighting") {
        // Files of voxhap before the weighting was typed wrote "" for CT and phantoms.
        if (text.empty()) return true;
        md.mrWeighting = parseEnum(parseMrWeighting(text), text, where, name, "an MR weighting (T1-weighted, ...)");
    } else if (name == "t1_kind") {
        md.t1Kind = parseEnum(parseT1Kind(text), text, where, name, "a T1 kind");
    } else if (name == "field_strength") {
        md.fieldStrength = parseEnum(parseFieldStrength(text), text, where, name, "1.5T or 3T");
    } else if (name == "field_strength_source") {
        md.fieldStrengthSource = parseEnum(parseFactSource(text), text, where, name, "a source (header, sidecar, ...)");
    } else if (name == "field_strength_tesla") {
        md.fieldStrengthTesla = parseNumber(text, where, name);
    } else if (name == "body_width_mm") {
        md.bodyWidthMm = parseNumber(text, where, name);
    } else if (name == "series_uid") {
        md.seriesUid = text;
    } else if (name == "volume") {
        choice().index = parseCount(text, where, name);
    } else if (name == "volume_count") {
        choice().count = parseCount(text, where, name);
    } else if (name == "volume_label") {
        choice().label = text;
    } else if (name == "layers") {
        md.phantomLayers = parseLayers(text, where, name);
    } else if (name == "landmarks") {
        md.landmarks = parseLandmarks(text, where, name);
    } else if (name == "fusion") {
        const auto j = nlohmann::json::parse(text, nullptr, false);
        if (j.is_discarded()) throw ValueError(where + ": fusion: not JSON");
        md.fusion = fusionRecordFromJson(j, where);
    } else {
        return false;
    }
    return true;
}

void upgradeLegacyExtras(VolumeMetadata& md, const std::string& where)
{
    auto& x = md.extra;
    const auto take = [&x](const char* key) -> std::optional<std::string> {
        const auto it = x.find(key);
        if (it == x.end()) return std::nullopt;
        std::string v = std::move(it->second);
        x.erase(it);
        return v;
    };
    // Only the phantoms wrote "field_strength", from their spec.
    if (auto f = take("field_strength"); f && !md.fieldStrength) {
        md.fieldStrength = parseEnum(parseFieldStrength(*f), *f, where, "field_strength", "1.5T or 3T");
        md.fieldStrengthSource = FactSource::Generator;
    }
    // A T1-weighted scan normalised per scan recorded the field it used and why.
    const auto normField = take("t1_norm_field");
    const auto normFieldSource = take("t1_norm_field_source");
    const auto fieldSource = take("field_strength_source"); // text: "assumed ..." when the headers were silent
    if (!md.fieldStrength && normField) {
        md.fieldStrength = parseEnum(parseFieldStrength(*normField), *normField, where, "t1_norm_field", "1.5T or 3T");
        md.fieldStrengthSource =
            normFieldSource && normFieldSource->rfind("assumed", 0) == 0 ? FactSource::Assumed : FactSource::Header;
    } else if (!md.fieldStrength && fieldSource && fieldSource->rfind("assumed", 0) == 0) {
        // The loaders' assumed field was 1.5 T whenever nothing normalised with another.
        md.fieldStrength = FieldStrength::T1_5;
        md.fieldStrengthSource = FactSource::Assumed;
    }
    if (auto k = take("t1_kind"); k && !md.t1Kind)
        md.t1Kind = parseEnum(parseT1Kind(*k), *k, where, "t1_kind", "a T1 kind");
    if (auto why = take("modality_source"); why && md.modalityReason.empty()) {
        md.modalityReason = *why;
        md.modalitySource = legacyModalitySource(*why);
    }
    if (auto w = take("body_width_mm"); w && !md.bodyWidthMm) md.bodyWidthMm = parseNumber(*w, where, "body_width_mm");
    if (auto uid = take("series_uid"); uid && md.seriesUid.empty()) md.seriesUid = *uid;
    if (auto vol = take("volume"); vol && !md.volumeChoice) {
        md.volumeChoice = legacyVolumeChoice(*vol);
        if (!md.volumeChoice) throw ValueError(badValue(where, "volume", *vol, "'N of M (label)'"));
    }
    if (auto l = take("layers"); l && !md.phantomLayers) md.phantomLayers = parseLayers(*l, where, "layers");
    if (auto m = take("landmarks"); m && md.landmarks.empty()) md.landmarks = parseLandmarks(*m, where, "landmarks");
}

} // namespace voxhap::volume
