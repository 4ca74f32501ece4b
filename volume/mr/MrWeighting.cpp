// SPDX-License-Identifier: Apache-2.0
/// @file MrWeighting.cpp
/// @brief The MR weighting rule (MrWeighting.h) and the BIDS sidecar reader.
#include "volume/mr/MrWeighting.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <numbers>
#include <regex>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace voxhap::volume {

// A named namespace rather than an anonymous one: the library is built in
// unity batches, where file-local names of several sources share one scope.
namespace mrweighting_detail {

std::string upper(std::string_view s)
{
    std::string r(s);
    std::transform(r.begin(), r.end(), r.begin(), [](unsigned char c) { return char(std::toupper(c)); });
    return r;
}

std::string lower(std::string_view s)
{
    std::string r(s);
    std::transform(r.begin(), r.end(), r.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return r;
}

std::string trim(std::string_view s)
{
    const auto isSpace = [](unsigned char c) { return std::isspace(c) != 0 || c == '\0'; };
    std::size_t b = 0, e = s.size();
    while (b < e && isSpace((unsigned char)s[b])) ++b;
    while (e > b && isSpace((unsigned char)s[e - 1])) --e;
    return std::string(s.substr(b, e - b));
}

/// Values of a multi-valued DICOM string ("ORIGINAL\PRIMARY\M\ND"), trimmed and
/// upper-cased; empty values dropped.
std::vector<std::string> dicomValues(std::string_view s)
{
    std::vector<std::string> out;
    std::size_t start = 0;
    while (start <= s.size()) {
        const std::size_t end = std::min(s.find('\\', start), s.size());
        std::string v = upper(trim(s.substr(start, end - start)));
        if (!v.empty()) out.push_back(std::move(v));
        start = end + 1;
    }
    return out;
}

/// @p v without spaces, underscores and hyphens: "T1 MAP", "T1_MAP" → "T1MAP".
std::string squeeze(std::string_view v)
{
    std::string r;
    for (char c : v) {
        if (c != ' ' && c != '_' && c != '-') r += c;
    }
    return r;
}

/// The words of a free-text field, upper-cased: runs of letters and digits.
/// "t1_MPRAGEcr_noGRAPPA" → T1, MPRAGECR, NOGRAPPA.
std::vector<std::string> words(std::string_view s)
{
    std::vector<std::string> out;
    std::string cur;
    for (char c : s) {
        if (std::isalnum((unsigned char)c)) {
            cur += char(std::toupper((unsigned char)c));
        } else if (!cur.empty()) {
            out.push_back(std::move(cur));
            cur.clear();
        }
    }
    if (!cur.empty()) out.push_back(std::move(cur));
    return out;
}

/// Letters and digits only, upper-cased: "gre_field-mapping" → "GREFIELDMAPPING".
/// Searched only for long, distinctive words.
std::string joined(std::string_view s)
{
    std::string r;
    for (char c : s) {
        if (std::isalnum((unsigned char)c)) r += char(std::toupper((unsigned char)c));
    }
    return r;
}

std::string fmt(double x)
{
    std::ostringstream o;
    o << std::setprecision(4) << x;
    return o.str();
}

bool has(const std::vector<std::string>& v, std::string_view x) { return std::find(v.begin(), v.end(), x) != v.end(); }

bool startsWith(std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; }

/// Two consecutive words @p a then @p b.
bool adjacent(const std::vector<std::string>& w, std::string_view a, std::string_view b)
{
    for (std::size_t i = 0; i + 1 < w.size(); ++i) {
        if (w[i] == a && w[i + 1] == b) return true;
    }
    return false;
}

/// One free-text field (SeriesDescription or ProtocolName), prepared for matching.
struct TextField {
    const char* label; ///< "SeriesDescription" or "ProtocolName"
    std::string value; ///< as given, trimmed
    std::vector<std::string> words;
    std::string joined;
};

/// What the rule looks at, parsed once.
struct Facts {
    std::vector<std::string> imageType, imageTypeSqueezed, scanning, variant, options;
    std::string seqRaw;           ///< sequence name as given, trimmed
    std::string seqLower;         ///< lower-case, leading '*' removed: "tfl3d1_ns"
    std::string seqUpperSqueezed; ///< upper-case without '-', '_', ' ': Philips "T1TFE"
    std::vector<TextField> text;  ///< description, then protocol name (non-empty only)
    std::optional<double> tr, te, ti, flip, b;
};

Facts parse(const MrSequenceFields& f)
{
    Facts x;
    x.imageType = dicomValues(f.imageType);
    for (const auto& v : x.imageType) x.imageTypeSqueezed.push_back(squeeze(v));
    x.scanning = dicomValues(f.scanningSequence);
    x.variant = dicomValues(f.sequenceVariant);
    x.options = dicomValues(f.scanOptions);
    x.seqRaw = trim(f.sequenceName);
    x.seqLower = lower(x.seqRaw);
    while (!x.seqLower.empty() && x.seqLower.front() == '*') x.seqLower.erase(0, 1);
    x.seqUpperSqueezed = squeeze(upper(x.seqLower));
    for (const auto& [label, value] :
        {std::pair{"SeriesDescription", &f.description}, std::pair{"ProtocolName", &f.protocolName}}) {
        const std::string v = trim(*value);
        if (!v.empty()) x.text.push_back({label, v, words(v), joined(v)});
    }
    const auto finite = [](const std::optional<double>& v) -> std::optional<double> {
        return v && std::isfinite(*v) && *v >= 0 ? v : std::nullopt;
    };
    x.tr = finite(f.repetitionTimeMs);
    x.te = finite(f.echoTimeMs);
    x.ti = finite(f.inversionTimeMs);
    x.flip = finite(f.flipAngleDeg);
    x.b = finite(f.bValue);
    return x;
}

MrWeighting verdict(MrWeightingKind k, std::string reason, const MrSequenceFields& f)
{
    MrWeighting w;
    w.kind = k;
    w.name = std::string(mrWeightingName(k));
    w.reason = std::move(reason);
    if (!trim(f.source).empty()) w.reason += " (from " + trim(f.source) + ")";
    return w;
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

// ---------------------------------------------------------------- stage 1

/// Stage 2's field-map purpose, also needed by stage 1 to name a phase
/// difference: returns the evidence, or empty.
std::string fieldMapEvidence(const Facts& x)
{
    static const std::regex siemensFm("^fm[0-9]");
    if (std::regex_search(x.seqLower, siemensFm)) return "sequence name " + x.seqRaw + " (Siemens field map)";
    for (const auto& t : x.text) {
        if (t.joined.find("FIELDMAP") != std::string::npos || t.joined.find("B0MAP") != std::string::npos ||
            has(t.words, "FMAP") || has(t.words, "TOPUP") || adjacent(t.words, "B0", "FIELD")) {
            return std::string(t.label) + " " + quoted(t.value);
        }
    }
    return {};
}

std::optional<MrWeighting> imageTypeVerdict(const Facts& x, const MrSequenceFields& f)
{
    if (x.imageType.empty()) return std::nullopt;
    const std::string it = "ImageType " + trim(f.imageType);
    const auto anyOf = [&](std::initializer_list<std::string_view> names) -> std::string {
        for (std::size_t i = 0; i < x.imageType.size(); ++i) {
            for (auto n : names) {
                if (x.imageTypeSqueezed[i] == n) return x.imageType[i];
            }
        }
        return {};
    };
    std::string hit;
    if (!(hit = anyOf({"T1MAP"})).empty() || adjacent(x.imageType, "T1", "MAP")) {
        return verdict(MrWeightingKind::T1Map, it + " names a T1 map", f);
    }
    if (!(hit = anyOf({"P", "PHASE", "PHASEMAP"})).empty() ||
        std::any_of(x.imageType.begin(), x.imageType.end(), [](const std::string& v) { return startsWith(v, "P_"); })) {
        const std::string fm = fieldMapEvidence(x);
        if (!fm.empty()) {
            return verdict(MrWeightingKind::FieldMap, it + " is a phase image of a field-map sequence (" + fm + ")", f);
        }
        return verdict(MrWeightingKind::Phase, it + " says phase", f);
    }
    if (!(hit = anyOf({"B0MAP", "B0", "FIELDMAP", "FIELDMAPHZ"})).empty()) {
        return verdict(MrWeightingKind::FieldMap, it + ": " + hit + " is a B0 field map", f);
    }
    if (!(hit = anyOf({"B1MAP", "B1", "TB1MAP", "FLIPANGLEMAP"})).empty()) {
        return verdict(MrWeightingKind::FieldMap, it + ": " + hit + " is a B1 (RF) field map", f);
    }
    if (!(hit = anyOf({"DIFFUSION", "ADC", "EADC", "FA", "COLFA", "TRACEW", "TRACE", "TENSOR"})).empty()) {
        return verdict(
            MrWeightingKind::Diffusion, it + ": " + hit + " is diffusion weighting or a map derived from it", f);
    }
    if (!(hit = anyOf({"PERFUSION", "PERF", "ASL", "CBF", "CBV", "MTT", "TTP", "RELCBF", "RELCBV", "RELMTT"}))
             .empty()) {
        return verdict(MrWeightingKind::Perfusion, it + ": " + hit + " is perfusion", f);
    }
    if (!(hit = anyOf({"FMRI"})).empty()) return verdict(MrWeightingKind::Functional, it + ": FMRI", f);
    if (!(hit = anyOf({"SWI", "QSM", "MNIP", "MINIP"})).empty()) {
        return verdict(MrWeightingKind::Susceptibility, it + ": " + hit + " is susceptibility weighting", f);
    }
    if (!(hit = anyOf({"FAT", "FF", "FATFRACTION", "WATERFRACTION", "R2STAR", "T2STAR", "MTR"})).empty()) {
        return verdict(MrWeightingKind::OtherMap, it + ": " + hit + " is a quantitative map, not T1", f);
    }
    for (std::size_t i = 0; i < x.imageType.size(); ++i) {
        const std::string& s = x.imageTypeSqueezed[i];
        if (s.size() > 3 && s.compare(s.size() - 3, 3, "MAP") == 0) {
            return verdict(MrWeightingKind::OtherMap, it + ": " + x.imageType[i] + " is a quantitative map, not T1", f);
        }
    }
    if (!(hit = anyOf({"MIP", "SUB", "SUBTRACTION", "PROJECTIONIMAGE"})).empty()) {
        return verdict(
            MrWeightingKind::Derived, it + ": " + hit + " is a projection or subtraction, not a tissue image", f);
    }
    return std::nullopt;
}

// ---------------------------------------------------------------- stage 2

std::optional<MrWeighting> purposeVerdict(const Facts& x, const MrSequenceFields& f)
{
    const auto textHit = [&](auto&& pred) -> std::string {
        for (const auto& t : x.text) {
            if (pred(t)) return std::string(t.label) + " " + quoted(t.value);
        }
        return {};
    };
    const auto because = [](const std::string& evidence, const char* what) {
        return evidence + " makes it " + what + ", whatever its TR, TE and flip angle";
    };

    if (std::string e = fieldMapEvidence(x); !e.empty()) {
        return verdict(MrWeightingKind::FieldMap, because(e, "a field map"), f);
    }

    // Diffusion.
    static const std::regex siemensDiffusion("(^|[^a-z])(ep|re)_b[0-9]");
    static const std::regex dwiWord("^(DWI|DTI|DMRI)[0-9]*$");
    if (std::regex_search(x.seqLower, siemensDiffusion)) {
        return verdict(MrWeightingKind::Diffusion,
            because("sequence name " + x.seqRaw + " (Siemens diffusion EPI)", "diffusion"), f);
    }
    if (startsWith(x.seqUpperSqueezed, "DWI")) {
        return verdict(
            MrWeightingKind::Diffusion, because("sequence name " + x.seqRaw + " (Philips diffusion)", "diffusion"), f);
    }
    if (x.b && *x.b > 0) {
        return verdict(MrWeightingKind::Diffusion, because("b-value " + fmt(*x.b) + " s/mm²", "diffusion"), f);
    }
    if (std::string e = textHit([](const TextField& t) {
            return t.joined.find("DIFFUSION") != std::string::npos ||
                std::any_of(t.words.begin(), t.words.end(), [](const std::string& w) {
                    static const std::vector<std::string> k{
                        "DIFF", "HARDI", "TENSOR", "TRACEW", "ADC", "MDDW", "RESOLVE", "NODDI", "IVIM", "DKI", "DWIBS"};
                    return std::regex_match(w, dwiWord) || has(k, w);
                });
        });
        !e.empty()) {
        return verdict(MrWeightingKind::Diffusion, because(e, "diffusion"), f);
    }

    // Perfusion.
    if (x.seqLower.find("asl") != std::string::npos) {
        return verdict(MrWeightingKind::Perfusion,
            because("sequence name " + x.seqRaw + " (arterial spin labelling)", "perfusion"), f);
    }
    if (std::string e = textHit([](const TextField& t) {
            static const std::vector<std::string> k{"ASL", "PASL", "PCASL", "CASL", "PERF", "DSC", "DCE", "CBF", "PWI"};
            return t.joined.find("PERFUSION") != std::string::npos ||
                std::any_of(t.words.begin(), t.words.end(), [](const std::string& w) { return has(k, w); });
        });
        !e.empty()) {
        return verdict(MrWeightingKind::Perfusion, because(e, "perfusion"), f);
    }

    // Susceptibility.
    if (x.seqLower.find("swi") != std::string::npos || x.seqLower.find("swan") != std::string::npos) {
        return verdict(
            MrWeightingKind::Susceptibility, because("sequence name " + x.seqRaw, "susceptibility-weighted"), f);
    }
    if (std::string e = textHit([](const TextField& t) {
            static const std::vector<std::string> k{"SWAN", "SWIP", "QSM", "VENBOLD"};
            return t.joined.find("SUSCEPTIBILITY") != std::string::npos || adjacent(t.words, "VEN", "BOLD") ||
                std::any_of(t.words.begin(), t.words.end(),
                    [](const std::string& w) { return startsWith(w, "SWI") || has(k, w); });
        });
        !e.empty()) {
        return verdict(MrWeightingKind::Susceptibility, because(e, "susceptibility-weighted"), f);
    }

    // Functional.
    if (x.seqLower.find("epirt") != std::string::npos) {
        return verdict(
            MrWeightingKind::Functional, because("sequence name " + x.seqRaw + " (GE real-time EPI)", "functional"), f);
    }
    if (std::string e = textHit([](const TextField& t) {
            static const std::vector<std::string> k{"BOLD", "FMRI", "RSFMRI", "RFMRI", "TFMRI"};
            return t.joined.find("RESTINGSTATE") != std::string::npos ||
                std::any_of(t.words.begin(), t.words.end(), [](const std::string& w) { return has(k, w); });
        });
        !e.empty()) {
        return verdict(MrWeightingKind::Functional, because(e, "functional (BOLD)"), f);
    }

    // Angiography.
    static const std::regex angioWord("^(2D|3D)?(TOF|MRA|CEMRA)(2D|3D)?$");
    if (x.seqLower.find("tof") != std::string::npos) {
        return verdict(
            MrWeightingKind::Angiography, because("sequence name " + x.seqRaw + " (time of flight)", "angiography"), f);
    }
    if (std::string e = textHit([](const TextField& t) {
            return t.joined.find("ANGIO") != std::string::npos ||
                std::any_of(t.words.begin(), t.words.end(),
                    [](const std::string& w) { return std::regex_match(w, angioWord); });
        });
        !e.empty()) {
        return verdict(MrWeightingKind::Angiography, because(e, "angiography"), f);
    }

    // Localizers and calibration scans.
    if (std::string e = textHit([](const TextField& t) {
            static const std::vector<std::string> k{"SURVEY", "LOC", "3PLANE", "TRIPILOT", "CALIBRATION", "PRESCAN"};
            return t.joined.find("LOCALIZER") != std::string::npos || t.joined.find("LOCALISER") != std::string::npos ||
                t.joined.find("SCOUT") != std::string::npos || adjacent(t.words, "3", "PLANE") ||
                std::any_of(t.words.begin(), t.words.end(), [](const std::string& w) { return has(k, w); });
        });
        !e.empty()) {
        return verdict(MrWeightingKind::Localizer, because(e, "a localizer or calibration scan"), f);
    }
    return std::nullopt;
}

// ---------------------------------------------------------------- stage 3

/// The sequence families vendors' sequence names announce.
enum class Family {
    None,
    SpinEcho,
    InversionSpinEcho,
    Spoiled,
    SpoiledPrepared,
    SteadyState,
    GradientEcho,
    GreEpi,
    SeEpi,
    Epi
};

struct SequenceFamily {
    Family family = Family::None;
    std::string label;     ///< e.g. "Siemens tfl (TurboFLASH)"
    bool t1ByName = false; ///< the vendor's name says T1 (Philips T1-FFE, T1-TFE)
};

SequenceFamily sequenceFamily(const Facts& x)
{
    const std::string& n = x.seqLower;
    const std::string& P = x.seqUpperSqueezed;
    if (n.empty()) return {};
    const auto name = [&](const char* what) { return "sequence " + x.seqRaw + " (" + what + ")"; };
    // Philips (PulseSequenceName) first: whole names.
    if (P == "T1TFE") return {Family::SpoiledPrepared, name("Philips T1 turbo field echo"), true};
    if (P == "T1FFE") return {Family::Spoiled, name("Philips T1 fast field echo, spoiled"), true};
    if (P == "TFE") return {Family::SpoiledPrepared, name("Philips turbo field echo"), false};
    if (P == "BTFE" || P == "BFFE" || P == "T2FFE")
        return {Family::SteadyState, name("Philips steady-state field echo"), false};
    if (P == "FFE") return {Family::GradientEcho, name("Philips fast field echo"), false};
    if (P == "FEEPI") return {Family::GreEpi, name("Philips gradient-echo EPI"), false};
    if (P == "SEEPI") return {Family::SeEpi, name("Philips spin-echo EPI"), false};
    if (P == "TSE" || P == "SE") return {Family::SpinEcho, name("Philips spin echo"), false};
    if (P == "IR" || P == "IRTSE" || P == "IRSE" || P == "TIR")
        return {Family::InversionSpinEcho, name("Philips inversion recovery"), false};
    // GE names (anywhere in the name).
    for (const char* g : {"fspgr", "spgr", "efgre3d", "bravo", "lava"}) {
        if (n.find(g) != std::string::npos) return {Family::Spoiled, name("GE spoiled gradient echo"), false};
    }
    if (n.find("fiesta") != std::string::npos)
        return {Family::SteadyState, name("GE FIESTA, balanced steady state"), false};
    if (n.find("fse") != std::string::npos || n.find("cube") != std::string::npos) {
        return {Family::SpinEcho, name("GE fast spin echo"), false};
    }
    if (n.find("fgre") != std::string::npos) return {Family::GradientEcho, name("GE fast gradient echo"), false};
    // Siemens names: a prefix, then dimension and counters ("tfl3d1_ns", "tse2d1_15").
    // Short prefixes count only when a digit (the dimension) follows: "fl3d1", not "flair".
    const auto prefixDigit = [&](std::string_view p) {
        return startsWith(n, p) && n.size() > p.size() && std::isdigit((unsigned char)n[p.size()]);
    };
    if (startsWith(n, "tfl")) return {Family::SpoiledPrepared, name("Siemens TurboFLASH"), false};
    if (prefixDigit("fl")) return {Family::Spoiled, name("Siemens FLASH, spoiled gradient echo"), false};
    if (prefixDigit("tfi") || prefixDigit("ci") || startsWith(n, "psif") || prefixDigit("de") || prefixDigit("fi")) {
        return {Family::SteadyState, name("Siemens FISP/TrueFISP/PSIF/CISS/DESS steady state"), false};
    }
    if (startsWith(n, "epfid")) return {Family::GreEpi, name("Siemens gradient-echo EPI"), false};
    if (startsWith(n, "epse")) return {Family::SeEpi, name("Siemens spin-echo EPI"), false};
    if (startsWith(n, "spcir") || prefixDigit("tir") || prefixDigit("ir")) {
        return {Family::InversionSpinEcho, name("Siemens turbo inversion recovery"), false};
    }
    if (startsWith(n, "tse") || startsWith(n, "spc") || prefixDigit("h") || startsWith(n, "haste") ||
        prefixDigit("se")) {
        return {Family::SpinEcho, name("Siemens (turbo) spin echo"), false};
    }
    if (startsWith(n, "ep")) return {Family::Epi, name("EPI"), false};
    return {};
}

/// Stage 3's outcome: a verdict, or why the sequence fields did not decide.
struct ContrastOutcome {
    std::optional<MrWeighting> verdict;
    std::string undecided; ///< non-empty when the fields were read but did not decide
};

std::string sequenceLabel(const MrSequenceFields& f, const SequenceFamily& fam)
{
    std::string s;
    if (!trim(f.scanningSequence).empty()) s = "ScanningSequence " + trim(f.scanningSequence);
    if (!trim(f.sequenceVariant).empty())
        s += (s.empty() ? "" : ", ") + std::string("SequenceVariant ") + trim(f.sequenceVariant);
    if (!fam.label.empty()) s += (s.empty() ? "" : ", ") + fam.label;
    return s;
}

ContrastOutcome spinEchoTable(const Facts& x, const MrSequenceFields& f, const std::string& label)
{
    if (!x.tr || !x.te) return {std::nullopt, label + " without " + (!x.tr ? "TR" : "TE")};
    const double tr = *x.tr, te = *x.te;
    const std::string trte = label + " with TR " + fmt(tr) + " ms and TE " + fmt(te) + " ms";
    if (tr <= kMrSeShortTrMaxMs && te <= kMrShortTeMaxMs) {
        return {verdict(MrWeightingKind::T1Weighted,
                    trte + ": short TR (≤ " + fmt(kMrSeShortTrMaxMs) + ") and short TE (≤ " + fmt(kMrShortTeMaxMs) +
                        "), T1-weighted spin echo",
                    f),
            {}};
    }
    if (tr >= kMrSeLongTrMinMs && te <= kMrShortTeMaxMs) {
        return {verdict(MrWeightingKind::PdWeighted,
                    trte + ": long TR (≥ " + fmt(kMrSeLongTrMinMs) + ") and short TE (≤ " + fmt(kMrShortTeMaxMs) +
                        "), proton-density-weighted spin echo",
                    f),
            {}};
    }
    if (tr >= kMrSeLongTrMinMs && te >= kMrLongTeMinMs) {
        return {verdict(MrWeightingKind::T2Weighted,
                    trte + ": long TR (≥ " + fmt(kMrSeLongTrMinMs) + ") and long TE (≥ " + fmt(kMrLongTeMinMs) +
                        "), T2-weighted spin echo",
                    f),
            {}};
    }
    return {std::nullopt,
        trte + " lies between the T1 (TR ≤ " + fmt(kMrSeShortTrMaxMs) + ", TE ≤ " + fmt(kMrShortTeMaxMs) +
            "), PD (TR ≥ " + fmt(kMrSeLongTrMinMs) + ", TE ≤ " + fmt(kMrShortTeMaxMs) + ") and T2 (TR ≥ " +
            fmt(kMrSeLongTrMinMs) + ", TE ≥ " + fmt(kMrLongTeMinMs) + ") corners"};
}

ContrastOutcome contrastVerdict(const Facts& x, const MrSequenceFields& f)
{
    const SequenceFamily fam = sequenceFamily(x);
    const bool hasSE = has(x.scanning, "SE"), hasIR = has(x.scanning, "IR"), hasGR = has(x.scanning, "GR"),
               hasEP = has(x.scanning, "EP");
    const bool optionIR = has(x.options, "IR") || has(x.options, "IR_GEMS");
    const bool isIR = hasIR || optionIR || (x.ti && *x.ti > 0) || fam.family == Family::InversionSpinEcho;
    const bool isEPI =
        hasEP || fam.family == Family::GreEpi || fam.family == Family::SeEpi || fam.family == Family::Epi;
    const bool isSE = hasSE || fam.family == Family::SpinEcho || fam.family == Family::InversionSpinEcho ||
        fam.family == Family::SeEpi;
    const bool isGR = hasGR || fam.family == Family::Spoiled || fam.family == Family::SpoiledPrepared ||
        fam.family == Family::SteadyState || fam.family == Family::GradientEcho || fam.family == Family::GreEpi;
    const std::string label = sequenceLabel(f, fam);
    if (label.empty() && !x.tr && !x.te && !x.ti && !x.flip) return {};
    const std::string seq = label.empty() ? std::string("the sequence") : label;

    // Inversion recovery: the inversion time sets the contrast.
    if (isIR) {
        if (x.ti && *x.ti > 0) {
            const double ti = *x.ti;
            const std::string withTi = seq + " with TI " + fmt(ti) + " ms";
            if (ti >= kMrFlairMinTiMs) {
                return {verdict(MrWeightingKind::Flair,
                            withTi + " ≥ " + fmt(kMrFlairMinTiMs) +
                                " ms: long-TI inversion recovery, fluid nulled (FLAIR type), not T1",
                            f),
                    {}};
            }
            if (ti <= kMrStirMaxTiMs) {
                return {verdict(MrWeightingKind::Stir,
                            withTi + " ≤ " + fmt(kMrStirMaxTiMs) +
                                " ms: short-TI inversion recovery, fat nulled (STIR), not T1",
                            f),
                    {}};
            }
            const std::string mid = withTi + " between STIR (≤ " + fmt(kMrStirMaxTiMs) + " ms) and FLAIR (≥ " +
                fmt(kMrFlairMinTiMs) + " ms)";
            if (x.te && isGR && !isSE && *x.te >= kMrT2StarMinTeMs) {
                return {verdict(MrWeightingKind::T2StarWeighted,
                            mid + " but TE " + fmt(*x.te) + " ms ≥ " + fmt(kMrT2StarMinTeMs) + " ms: T2*-weighted", f),
                    {}};
            }
            if (x.te && !isGR && *x.te >= kMrLongTeMinMs) {
                return {verdict(MrWeightingKind::T2Weighted,
                            mid + " but TE " + fmt(*x.te) + " ms ≥ " + fmt(kMrLongTeMinMs) +
                                " ms: T2-weighted inversion recovery",
                            f),
                    {}};
            }
            const char* type = isGR ? ": inversion-prepared gradient echo (MPRAGE type), T1-weighted"
                : isSE              ? ": T1-weighted inversion recovery (T1-FLAIR type)"
                                    : ": T1-weighted inversion recovery";
            return {verdict(MrWeightingKind::T1Weighted, mid + type, f), {}};
        }
        if (fam.t1ByName) {
            return {verdict(MrWeightingKind::T1Weighted,
                        seq + ": inversion-prepared without a TI; the vendor names it T1-weighted", f),
                {}};
        }
        return {std::nullopt, seq + ": inversion recovery without an inversion time"};
    }

    // Echo planar (diffusion, perfusion and BOLD purposes were stage 2's).
    if (isEPI) {
        if (isSE && !isGR) return spinEchoTable(x, f, seq + " (spin-echo EPI)");
        if (isGR) {
            if (x.te && *x.te >= kMrT2StarMinTeMs) {
                return {verdict(MrWeightingKind::T2StarWeighted,
                            seq + " with TE " + fmt(*x.te) + " ms ≥ " + fmt(kMrT2StarMinTeMs) +
                                " ms: gradient-echo EPI, T2*-weighted (BOLD-type contrast)",
                            f),
                    {}};
            }
            return {std::nullopt, seq + ": gradient-echo EPI without a long TE"};
        }
        return {std::nullopt, seq + ": EPI whose echo type (gradient or spin echo) is not given"};
    }

    // Spin echo and turbo spin echo.
    if (isSE) return spinEchoTable(x, f, seq);

    // Gradient echo.
    if (isGR) {
        if (fam.family == Family::SteadyState || has(x.variant, "TRSS")) {
            return {verdict(MrWeightingKind::SteadyState,
                        seq + ": balanced or coherent steady state (T2/T1 contrast), not T1", f),
                {}};
        }
        if (x.te && *x.te >= kMrT2StarMinTeMs) {
            return {verdict(MrWeightingKind::T2StarWeighted,
                        seq + " with TE " + fmt(*x.te) + " ms ≥ " + fmt(kMrT2StarMinTeMs) +
                            " ms: T2*-weighted gradient echo",
                        f),
                {}};
        }
        const bool spoiled =
            has(x.variant, "SP") || fam.family == Family::Spoiled || fam.family == Family::SpoiledPrepared;
        const bool prepared = has(x.variant, "MP") || fam.family == Family::SpoiledPrepared;
        if (!spoiled) return {std::nullopt, seq + ": a gradient echo whose spoiling is not given"};
        if (prepared) {
            if (fam.t1ByName) {
                return {verdict(MrWeightingKind::T1Weighted,
                            seq + ": magnetization-prepared spoiled gradient echo; the vendor names it T1-weighted", f),
                    {}};
            }
            return {std::nullopt,
                seq +
                    ": magnetization-prepared gradient echo without an inversion time (its preparation, not "
                    "its flip angle, sets the contrast)"};
        }
        if (x.tr && *x.tr > 0 && x.flip) {
            const double w = spoiledGreT1Sensitivity(*x.tr, *x.flip, kMrReferenceT1Ms);
            const double ernst = std::acos(std::exp(-*x.tr / kMrReferenceT1Ms)) * 180.0 / std::numbers::pi;
            const std::string why = seq + " with TR " + fmt(*x.tr) + " ms, TE " +
                (x.te ? fmt(*x.te) : std::string("?")) + " ms, flip " + fmt(*x.flip) + "° (Ernst angle " + fmt(ernst) +
                "° for T1 " + fmt(kMrReferenceT1Ms) + " ms): T1 sensitivity " + fmt(w);
            if (w >= kMrMinT1Sensitivity) {
                return {verdict(MrWeightingKind::T1Weighted,
                            why + " ≥ " + fmt(kMrMinT1Sensitivity) + ", T1-weighted spoiled gradient echo", f),
                    {}};
            }
            return {verdict(MrWeightingKind::PdWeighted,
                        why + " < " + fmt(kMrMinT1Sensitivity) + ": small flip for its TR, proton-density-weighted", f),
                {}};
        }
        if (fam.t1ByName) {
            return {verdict(MrWeightingKind::T1Weighted,
                        seq + ": spoiled gradient echo the vendor names T1-weighted (no TR or flip angle given)", f),
                {}};
        }
        return {std::nullopt, seq + ": spoiled gradient echo without " + std::string(!x.tr ? "TR" : "a flip angle")};
    }
    if (label.empty()) return {std::nullopt, "TR, TE, TI or flip angle without a sequence type"};
    return {std::nullopt, seq + ": no spin-echo, gradient-echo or inversion-recovery type"};
}

// ---------------------------------------------------------------- stage 4

enum class Named {
    T1Map,
    T1,
    T2,
    T2Star,
    Pd,
    Flair,
    Stir
};

std::string_view namedWord(Named n)
{
    switch (n) {
    case Named::T1Map:
        return "T1 map";
    case Named::T1:
        return "T1";
    case Named::T2:
        return "T2";
    case Named::T2Star:
        return "T2*";
    case Named::Pd:
        return "PD";
    case Named::Flair:
        return "FLAIR";
    case Named::Stir:
        return "STIR";
    }
    return "";
}

/// The contrasts one free-text field names, on whole words.
std::vector<Named> namedContrasts(const TextField& t)
{
    static const std::regex t1Word(
        "^((2D|3D)?T1(W|WI|WEIGHTED|C|CE|GD|POST|PRE|SE|TSE|FSE|FFE|TFE|GRE|SPGR|VIBE|MPRAGE|MPR|"
        "SPACE|SPC|CUBE|VISTA|IR|FLAIR)?|ST1W)$");
    static const std::regex t2Word(
        "^((2D|3D)?T2(W|WI|WEIGHTED|SE|TSE|FSE|FRFSE|FFE|SPACE|SPC|CUBE|VISTA|HASTE|BLADE|PROPELLER|DRIVE)?|ST2W)$");
    static const std::regex pdWord("^((2D|3D)?PD(W|WI|WEIGHTED|SE|TSE|FSE|FS|FATSAT|SPACE|SPC|CUBE|VISTA)?|SPDW)$");
    static const std::regex stirWord("^(T2)?STIR$");
    const auto& w = t.words;
    std::vector<Named> out;
    const auto add = [&](Named n) {
        if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
    };
    bool t1Flair = false;
    for (std::size_t i = 0; i < w.size(); ++i) {
        const std::string& s = w[i];
        const bool nextMap = i + 1 < w.size() && w[i + 1] == "MAP";
        if (s == "T1MAP" || (s == "T1" && nextMap)) {
            add(Named::T1Map);
            continue;
        }
        if (std::regex_match(s, t1Word)) {
            add(Named::T1);
            if (s.find("FLAIR") != std::string::npos || (i + 1 < w.size() && w[i + 1] == "FLAIR")) t1Flair = true;
            continue;
        }
        if (s == "T2STAR" || (s == "T2" && i + 1 < w.size() && w[i + 1] == "STAR")) {
            add(Named::T2Star);
            continue;
        }
        if (std::regex_match(s, t2Word) || s == "HASTE" || s == "SSFSE") add(Named::T2);
        if (std::regex_match(s, pdWord) || (s == "PROTON" && i + 1 < w.size() && w[i + 1] == "DENSITY")) add(Named::Pd);
        if (s.find("FLAIR") != std::string::npos || s == "DARKFLUID" ||
            (s == "DARK" && i + 1 < w.size() && w[i + 1] == "FLUID")) {
            add(Named::Flair);
        }
        if (std::regex_match(s, stirWord)) add(Named::Stir);
        static const std::vector<std::string> t1Family{"VIBE", "LAVA", "T1FFE", "T1TFE"};
        if (has(t1Family, s)) add(Named::T1);
    }
    for (const char* sub : {"MPRAGE", "SPGR", "BRAVO", "THRIVE"}) {
        if (t.joined.find(sub) != std::string::npos) add(Named::T1);
    }
    if (t.value.find("T2*") != std::string::npos || t.value.find("t2*") != std::string::npos) add(Named::T2Star);
    if (t1Flair) out.erase(std::remove(out.begin(), out.end(), Named::Flair), out.end()); // T1-FLAIR is T1-weighted
    if (std::find(out.begin(), out.end(), Named::T2Star) != out.end()) {
        out.erase(std::remove(out.begin(), out.end(), Named::T2), out.end());
    }
    return out;
}

std::optional<MrWeighting> descriptionVerdict(const Facts& x, const MrSequenceFields& f, const std::string& undecided)
{
    const std::string tail = undecided.empty() ? std::string{} : "; the sequence fields did not (" + undecided + ")";
    for (const auto& t : x.text) {
        std::vector<Named> n = namedContrasts(t);
        if (n.empty()) continue;
        const std::string field = std::string(t.label) + " " + quoted(t.value);
        const auto contains = [&](Named k) { return std::find(n.begin(), n.end(), k) != n.end(); };
        if (contains(Named::T1Map)) {
            return verdict(
                MrWeightingKind::T1Map, "only the description decided: " + field + " names a T1 map" + tail, f);
        }
        if (contains(Named::T1) && n.size() > 1) {
            std::string others;
            for (Named k : n) {
                if (k != Named::T1) others += (others.empty() ? "" : ", ") + std::string(namedWord(k));
            }
            return verdict(
                MrWeightingKind::Unknown, field + " names both T1 and " + others + ", so it decides nothing" + tail, f);
        }
        if (contains(Named::T1)) {
            return verdict(MrWeightingKind::T1Weighted,
                "only the description decided: " + field + " names a T1-weighted series" + tail, f);
        }
        // Not T1: the more specific name wins (FLAIR and STIR are T2-type; T2* removed T2 above).
        for (auto [k, kind] :
            {std::pair{Named::Flair, MrWeightingKind::Flair}, std::pair{Named::Stir, MrWeightingKind::Stir},
                std::pair{Named::T2Star, MrWeightingKind::T2StarWeighted}}) {
            if (contains(k)) {
                return verdict(
                    kind, "only the description decided: " + field + " names " + std::string(namedWord(k)) + tail, f);
            }
        }
        if (contains(Named::T2) && contains(Named::Pd)) {
            return verdict(MrWeightingKind::Unknown,
                field + " names both PD and T2 (a dual-echo series?), so it decides nothing" + tail, f);
        }
        const Named k = n.front();
        return verdict(k == Named::Pd ? MrWeightingKind::PdWeighted : MrWeightingKind::T2Weighted,
            "only the description decided: " + field + " names " + std::string(namedWord(k)) + tail, f);
    }
    return std::nullopt;
}

} // namespace mrweighting_detail

double spoiledGreT1Sensitivity(double trMs, double flipDeg, double t1Ms)
{
    if (!(trMs > 0) || !(t1Ms > 0) || !std::isfinite(trMs) || !std::isfinite(t1Ms) || !std::isfinite(flipDeg))
        return 0.0;
    const double x = trMs / t1Ms;
    const double oneMinusE = -std::expm1(-x); // 1 − E1, accurate for TR ≪ T1
    const double e = 1.0 - oneMinusE;
    const double c = std::cos(flipDeg * std::numbers::pi / 180.0);
    const double denom = (1.0 - c) + c * oneMinusE; // 1 − E1 cos α
    if (!(denom > 0)) return 0.0;
    return std::abs(x * e * (1.0 / oneMinusE - c / denom));
}

MrWeighting classifyMrWeighting(const MrSequenceFields& f)
{
    using namespace mrweighting_detail;
    const Facts x = parse(f);
    if (auto v = imageTypeVerdict(x, f)) return *v;
    if (auto v = purposeVerdict(x, f)) return *v;
    ContrastOutcome c = contrastVerdict(x, f);
    if (c.verdict) return *c.verdict;
    if (auto v = descriptionVerdict(x, f, c.undecided)) return *v;
    std::string why;
    if (!c.undecided.empty()) {
        why = c.undecided + "; no description keyword decides either";
    } else if (x.text.empty() && x.imageType.empty() && x.seqRaw.empty() && x.scanning.empty() && x.variant.empty() &&
        !x.tr && !x.te && !x.ti && !x.flip) {
        why =
            "no sequence fields were given (ScanningSequence, SequenceVariant, sequence name, TR, TE, TI, flip angle, "
            "ImageType, description)";
    } else {
        why = "none of the fields given decides the weighting";
    }
    return verdict(MrWeightingKind::Unknown, why + ": an intensity grid, never T1", f);
}

// ---------------------------------------------------------------- BIDS sidecars

fs::path bidsSidecarPath(const fs::path& image)
{
    fs::path p = image;
    std::string ext = mrweighting_detail::lower(p.extension().string());
    if (ext == ".gz") {
        p.replace_extension(); // x.nii.gz → x.nii
    }
    p.replace_extension(".json");
    return p;
}

namespace mrweighting_detail {

[[noreturn]] void sidecarFail(const fs::path& file, const std::string& field, const std::string& why)
{
    throw IoError(file.string() + ": " + (field.empty() ? why : field + ": " + why));
}

std::string oneLine(std::string s)
{
    std::replace(s.begin(), s.end(), '\n', ' ');
    std::replace(s.begin(), s.end(), '\r', ' ');
    if (s.rfind("[json.exception.", 0) == 0) {
        const auto close = s.find("] ");
        if (close != std::string::npos) s.erase(0, close + 2);
    }
    return s;
}

std::string sidecarString(const nlohmann::json& j, const char* key, const fs::path& file)
{
    if (!j.contains(key) || j.at(key).is_null()) return {};
    const auto& v = j.at(key);
    if (!v.is_string()) sidecarFail(file, key, std::string("must be a string, not ") + v.type_name());
    return v.get<std::string>();
}

/// A string, or an array of strings joined with DICOM's backslash.
std::string sidecarValues(const nlohmann::json& j, const char* key, const fs::path& file)
{
    if (!j.contains(key) || j.at(key).is_null()) return {};
    const auto& v = j.at(key);
    if (v.is_string()) return v.get<std::string>();
    if (v.is_array()) {
        std::string out;
        for (const auto& e : v) {
            if (!e.is_string())
                sidecarFail(file, key,
                    std::string("must be a string or an array of strings, not an array holding ") + e.type_name());
            out += (out.empty() ? "" : "\\") + e.get<std::string>();
        }
        return out;
    }
    sidecarFail(file, key, std::string("must be a string or an array of strings, not ") + v.type_name());
}

double checkedNumber(const nlohmann::json& v, const char* key, const fs::path& file, const char* unit)
{
    if (!v.is_number()) sidecarFail(file, key, std::string("must be a number [") + unit + "], not " + v.type_name());
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < 0)
        sidecarFail(file, key, "must be a finite, non-negative number [" + std::string(unit) + "], not " + fmt(x));
    return x;
}

std::optional<double> sidecarNumber(const nlohmann::json& j, const char* key, const fs::path& file, const char* unit)
{
    if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
    return checkedNumber(j.at(key), key, file, unit);
}

/// A BIDS time in seconds (a number, or an array of numbers whose first is
/// taken), returned in milliseconds.
std::optional<double> sidecarTimeMs(const nlohmann::json& j, const char* key, double maxS, const fs::path& file)
{
    if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
    const auto& v = j.at(key);
    double s = 0;
    if (v.is_array()) {
        if (v.empty()) sidecarFail(file, key, "is an empty array; expected a number in seconds");
        for (const auto& e : v) checkedNumber(e, key, file, "s");
        s = v.front().get<double>();
    } else {
        s = checkedNumber(v, key, file, "s");
    }
    if (s > maxS) {
        sidecarFail(file, key,
            fmt(s) + " s is implausible (more than " + fmt(maxS) +
                " s): BIDS times are in seconds; was it written in milliseconds?");
    }
    return s * 1000.0;
}

} // namespace mrweighting_detail

BidsSidecar readBidsSidecar(const fs::path& json)
{
    using namespace mrweighting_detail;
    std::error_code ec;
    if (!fs::exists(json, ec)) sidecarFail(json, "", "cannot open the BIDS sidecar");
    const std::string text = readBoundedFile(json, "BIDS sidecar"); // regular, at most 16 MiB
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) { // a syntax error, a number beyond double, ...
        sidecarFail(json, "", "malformed JSON: " + oneLine(e.what()));
    }
    if (!j.is_object())
        sidecarFail(json, "", std::string("a BIDS sidecar must be a JSON object, not ") + j.type_name());

    BidsSidecar s;
    s.file = json;
    MrSequenceFields& f = s.fields;
    f.scanningSequence = sidecarValues(j, "ScanningSequence", json);
    f.sequenceVariant = sidecarValues(j, "SequenceVariant", json);
    f.scanOptions = sidecarValues(j, "ScanOptions", json);
    f.imageType = sidecarValues(j, "ImageType", json);
    f.sequenceName = sidecarString(j, "SequenceName", json);
    if (trim(f.sequenceName).empty()) f.sequenceName = sidecarString(j, "PulseSequenceName", json);
    f.description = sidecarString(j, "SeriesDescription", json);
    f.protocolName = sidecarString(j, "ProtocolName", json);
    f.repetitionTimeMs = sidecarTimeMs(j, "RepetitionTime", kBidsMaxRepetitionTimeS, json);
    f.echoTimeMs = sidecarTimeMs(j, "EchoTime", kBidsMaxEchoTimeS, json);
    f.inversionTimeMs = sidecarTimeMs(j, "InversionTime", kBidsMaxInversionTimeS, json);
    f.flipAngleDeg = sidecarNumber(j, "FlipAngle", json, "deg");
    f.source = "BIDS sidecar " + json.filename().string();
    s.modality = trim(sidecarString(j, "Modality", json));
    s.fieldStrengthT = sidecarNumber(j, "MagneticFieldStrength", json, "T");
    if (s.fieldStrengthT && !(*s.fieldStrengthT > 0))
        sidecarFail(json, "MagneticFieldStrength", "must be positive [T]");
    return s;
}

std::optional<BidsSidecar> readBidsSidecarBeside(const fs::path& image)
{
    const fs::path p = bidsSidecarPath(image);
    std::error_code ec;
    if (p == image || !fs::is_regular_file(p, ec)) return std::nullopt;
    return readBidsSidecar(p);
}

} // namespace voxhap::volume
