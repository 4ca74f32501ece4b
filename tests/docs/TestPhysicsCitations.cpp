// SPDX-License-Identifier: Apache-2.0
/// @file TestPhysicsCitations.cpp
/// @brief Every citation of docs/physics.md in the tree names a section or a
/// regression case of it, and every quoted heading of docs/architecture.md exists.
///
/// What the checker reads: every file under the project root whose name ends in
/// .h, .hpp, .cpp, .cc, .in, .md, .json, .cmake, .sh or .py, and every
/// CMakeLists.txt; it skips hidden directories and build trees (a directory
/// holding CMakeCache.txt). Each file is read as UTF-8 and flattened first: on
/// every line the indentation and the comment leaders (/ * # !) are removed,
/// and the lines are joined by a space, so that a citation may wrap across a
/// comment line. Line numbers in messages are those of the original file.
///
/// What counts as a citation of a section (the section sign is written "S" here):
/// 1. "physics.md" followed by S and a number, or by a list or range of them:
///    "physics.md S1.2", "physics.md S1-S4", "physics.md S5.1/S5.4";
/// 2. "physics.md" followed by a bare number, or "section(s)" and a number,
///    with lists and ranges: "physics.md 5.1", "physics.md sections 2.1-2.3";
///    only whitespace may stand between "physics.md" and the number;
/// 3. S and a number anywhere else, with its list or range, unless the word
///    just before it names another document: a file name ending in ".md"
///    other than physics.md ("style.md S2"), a DICOM part ("PS3.5 S8.1.1"),
///    or a standard's number after RFC, ISO, IEC, IEEE, DIN, EN, NEMA or ASTM
///    ("RFC 1952 S2.2"). Those are left alone, and so is anything without the
///    section sign ("PS3.3 C.7.6.16"). The word before a wrapped S is the
///    last word of the line before.
/// A range "S1-S4" is checked at its two ends. A section resolves when
/// docs/physics.md has a heading (any level) that starts with its number,
/// optionally after the section sign: "### 1.2 Puncture resistance".
///
/// What counts as a citation of a regression case:
/// - S7 followed (after an optional ":" or ",") by "R" and a number: "S7 R1";
/// - in a file that cites S7 of physics.md anywhere, every free-standing token
///   "R" + digits ("R5", "TEST(R3, ...)"), except where an equals sign or an
///   asterisk follows it ("R1 = 1/T1", "R2*": relaxation rates).
/// A case resolves when docs/physics.md has a heading "R<n>" inside section 7.
///
/// Citations of the architecture page by a quoted name (its file name, then a
/// name in double quotes, as code comments write them) resolve when that page
/// has a heading or a bold term of that name.

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace {

namespace fs = std::filesystem;

const std::string kSign = "\xC2\xA7"; // the section sign, UTF-8
// The two page names, spelled in two pieces so that this file cites neither.
const std::string kPhysics = std::string("physics") + ".md";
const std::string kArchitecture = std::string("architecture") + ".md";
const std::string kEnDash = "\xE2\x80\x93";
const std::string kEmDash = "\xE2\x80\x94";

fs::path sourceDir() { return fs::path(VOXHAP_SOURCE_DIR); }

std::string readFile(const fs::path& p)
{
    std::ifstream in(p, std::ios::binary);
    std::ostringstream os;
    os << in.rdbuf();
    return os.str();
}

bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isWordChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; }
bool startsWith(std::string_view s, std::size_t at, std::string_view what)
{
    return s.size() >= at + what.size() && s.compare(at, what.size(), what) == 0;
}

/// A file's text with indentation and comment leaders removed and lines joined.
struct Flat {
    std::string text;
    std::vector<std::size_t> lineStart; ///< offset in text of each original line

    int lineOf(std::size_t pos) const
    {
        return int(std::upper_bound(lineStart.begin(), lineStart.end(), pos) - lineStart.begin());
    }
};

Flat flatten(std::string_view raw)
{
    Flat f;
    std::size_t start = 0;
    while (start <= raw.size()) {
        std::size_t end = raw.find('\n', start);
        if (end == std::string_view::npos) end = raw.size();
        std::string_view line = raw.substr(start, end - start);
        std::size_t i = 0;
        while (i < line.size() && std::string_view(" \t\r/*#!").find(line[i]) != std::string_view::npos) ++i;
        line.remove_prefix(i);
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
            line.remove_suffix(1);
        f.lineStart.push_back(f.text.size());
        f.text.append(line);
        f.text.push_back(' ');
        start = end + 1;
    }
    return f;
}

/// Parse a section number (digits, then ".digits" groups) at @p i; npos if none.
std::size_t parseNumber(std::string_view t, std::size_t i, std::string& out)
{
    if (i >= t.size() || !isDigit(t[i])) return std::string_view::npos;
    std::size_t j = i;
    while (j < t.size() && isDigit(t[j])) ++j;
    while (j + 1 < t.size() && t[j] == '.' && isDigit(t[j + 1])) {
        ++j;
        while (j < t.size() && isDigit(t[j])) ++j;
    }
    out.assign(t.substr(i, j - i));
    return j;
}

std::size_t skipSpaces(std::string_view t, std::size_t i)
{
    while (i < t.size() && (t[i] == ' ' || t[i] == '\t')) ++i;
    return i;
}

/// After a list element ending at @p i: the position just past a list or range
/// separator (",", ";", "/", "-", en or em dash, "and", "or", "to") and the
/// spaces after it; npos if none follows.
std::size_t skipSeparator(std::string_view t, std::size_t i)
{
    i = skipSpaces(t, i);
    for (std::string_view sep : {std::string_view(","), std::string_view(";"), std::string_view("/"),
             std::string_view("-"), std::string_view(kEnDash), std::string_view(kEmDash)}) {
        if (startsWith(t, i, sep)) return skipSpaces(t, i + sep.size());
    }
    for (std::string_view word : {"and", "or", "to"}) {
        if (startsWith(t, i, word) && i + word.size() < t.size() && t[i + word.size()] == ' ') {
            return skipSpaces(t, i + word.size());
        }
    }
    return std::string_view::npos;
}

/// A list of numbers starting at @p i, each preceded by the section sign when
/// @p withSign; returns the numbers and sets @p end past the last one.
std::vector<std::string> parseList(std::string_view t, std::size_t i, bool withSign, std::size_t& end)
{
    std::vector<std::string> out;
    end = i;
    for (;;) {
        std::size_t j = i;
        if (withSign) {
            if (!startsWith(t, j, kSign)) break;
            j = skipSpaces(t, j + kSign.size());
        }
        std::string number;
        const std::size_t after = parseNumber(t, j, number);
        if (after == std::string_view::npos) break;
        out.push_back(number);
        end = after;
        i = skipSeparator(t, after);
        if (i == std::string_view::npos) break;
    }
    return out;
}

/// True if the section sign at @p pos cites physics.md: the word before it
/// names physics.md, or names no document at all (rule 3 of the file comment).
bool belongsToPhysics(std::string_view t, std::size_t pos)
{
    std::size_t e = pos;
    while (e > 0 && std::string_view(" \t([{`\"'*:,;").find(t[e - 1]) != std::string_view::npos) --e;
    const auto wordBefore = [&](std::size_t end) {
        std::size_t b = end;
        while (b > 0 && (isWordChar(t[b - 1]) || t[b - 1] == '.' || t[b - 1] == '/' || t[b - 1] == '-')) --b;
        return std::pair(b, std::string(t.substr(b, end - b)));
    };
    auto [b, word] = wordBefore(e);
    while (!word.empty() && word.back() == '.') word.pop_back(); // "see style.md." is not a document name
    if (word.size() > 3 && word.compare(word.size() - 3, 3, ".md") == 0) {
        return word == kPhysics ||
            (word.size() > kPhysics.size() && word[word.size() - kPhysics.size() - 1] == '/' &&
                word.compare(word.size() - kPhysics.size(), kPhysics.size(), kPhysics) == 0);
    }
    static const std::vector<std::string> kStandards{"PS", "RFC", "ISO", "IEC", "IEEE", "DIN", "EN", "NEMA", "ASTM"};
    for (const std::string& s : kStandards) { // "PS3.5", "RFC1952"
        if (word.size() > s.size() && word.compare(0, s.size(), s) == 0 && isDigit(word[s.size()])) return false;
    }
    if (!word.empty() && isDigit(word[0])) { // "RFC 1952", "PS 3.5"
        std::size_t e2 = b;
        while (e2 > 0 && t[e2 - 1] == ' ') --e2;
        const std::string previous = wordBefore(e2).second;
        if (std::find(kStandards.begin(), kStandards.end(), previous) != kStandards.end()) return false;
    }
    return true;
}

struct Citation {
    enum Kind {
        Section,
        Case,
        ArchitectureName
    } kind;
    std::string id; ///< "1.2", "7" (Section), "1" (Case R1), a heading name (ArchitectureName)
    int line;
};

/// Every citation in one file's text (see the file comment for the rules).
std::vector<Citation> scanText(std::string_view raw)
{
    const Flat f = flatten(raw);
    const std::string_view t = f.text;
    std::vector<Citation> out;
    bool citesSeven = false;
    std::set<std::size_t> done;      // section signs already read as part of a list
    std::set<std::size_t> casesRead; // "R" tokens already read after a section sign

    // Rules 1 and 3: the section sign, with its list or range.
    for (std::size_t p = t.find(kSign); p != std::string_view::npos; p = t.find(kSign, p + 1)) {
        if (done.count(p)) continue;
        std::size_t end = 0;
        const std::vector<std::string> numbers = parseList(t, p, true, end);
        for (std::size_t q = t.find(kSign, p + 1); q != std::string_view::npos && q < end; q = t.find(kSign, q + 1)) {
            done.insert(q);
        }
        if (numbers.empty() || !belongsToPhysics(t, p)) continue;
        const int line = f.lineOf(p);
        for (const std::string& n : numbers) out.push_back({Citation::Section, n, line});
        // A case right after the last number: "S7 R1", "S7: R2".
        if (numbers.back() == "7") {
            citesSeven = true;
            std::size_t i = skipSpaces(t, end);
            if (i < t.size() && (t[i] == ':' || t[i] == ',')) i = skipSpaces(t, i + 1);
            std::string n;
            if (i < t.size() && t[i] == 'R' && parseNumber(t, i + 1, n) != std::string_view::npos &&
                n.find('.') == std::string::npos) {
                out.push_back({Citation::Case, n, f.lineOf(i)});
                casesRead.insert(i);
            }
        }
        if (std::find(numbers.begin(), numbers.end(), "7") != numbers.end()) citesSeven = true;
    }

    // Rule 2: "physics.md" and a bare number.
    for (std::size_t p = t.find(kPhysics); p != std::string_view::npos; p = t.find(kPhysics, p + 1)) {
        std::size_t i = p + kPhysics.size();
        const std::size_t spaces = skipSpaces(t, i);
        if (spaces == i) continue; // "physics.md:" or "physics.md," names the page, not a section
        i = spaces;
        for (std::string_view word : {"sections ", "section "}) {
            if (startsWith(t, i, word)) {
                i = skipSpaces(t, i + word.size());
                break;
            }
        }
        std::size_t end = 0;
        for (const std::string& n : parseList(t, i, false, end)) out.push_back({Citation::Section, n, f.lineOf(p)});
    }

    // Cases by name, in files that cite section 7.
    if (citesSeven) {
        for (std::size_t p = t.find('R'); p != std::string_view::npos; p = t.find('R', p + 1)) {
            if ((p > 0 && isWordChar(t[p - 1])) || casesRead.count(p)) continue;
            std::size_t j = p + 1;
            while (j < t.size() && isDigit(t[j])) ++j;
            if (j == p + 1 || (j < t.size() && isWordChar(t[j]))) continue;
            const std::size_t k = skipSpaces(t, j);
            if (k < t.size() && (t[k] == '=' || t[k] == '*')) continue; // a relaxation rate, not a case
            out.push_back({Citation::Case, std::string(t.substr(p + 1, j - p - 1)), f.lineOf(p)});
        }
    }

    // Quoted headings of architecture.md.
    for (std::size_t p = t.find(kArchitecture); p != std::string_view::npos; p = t.find(kArchitecture, p + 1)) {
        const std::size_t i = skipSpaces(t, p + kArchitecture.size());
        if (i >= t.size() || t[i] != '"') continue;
        const std::size_t close = t.find('"', i + 1);
        if (close == std::string_view::npos || close - i > 80) continue;
        out.push_back({Citation::ArchitectureName, std::string(t.substr(i + 1, close - i - 1)), f.lineOf(p)});
    }
    return out;
}

/// The headings of docs/physics.md: section numbers, and regression cases by
/// the top-level section they sit in.
struct PhysicsHeadings {
    std::set<std::string> sections;
    std::map<std::string, std::string> cases; ///< case number -> top-level section
};

PhysicsHeadings physicsHeadings(std::string_view md)
{
    PhysicsHeadings h;
    std::string top;
    std::istringstream in{std::string(md)};
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] != '#') continue;
        std::size_t i = line.find_first_not_of('#');
        if (i == std::string::npos) continue;
        i = skipSpaces(line, i);
        if (startsWith(line, i, kSign)) i = skipSpaces(line, i + kSign.size());
        std::string number;
        const std::size_t end = parseNumber(line, i, number);
        const auto endsWord = [&](std::size_t e) {
            return e >= line.size() || line[e] == '.' || line[e] == ' ' || line[e] == ':';
        };
        if (end != std::string::npos && endsWord(end)) {
            h.sections.insert(number);
            top = number.substr(0, number.find('.'));
        } else if (i < line.size() && line[i] == 'R') {
            const std::size_t e = parseNumber(line, i + 1, number);
            if (e != std::string::npos && endsWord(e) && number.find('.') == std::string::npos) h.cases[number] = top;
        }
    }
    return h;
}

/// Headings and bold terms of docs/architecture.md, without trailing "." or ":".
std::set<std::string> architectureNames(std::string_view md)
{
    std::set<std::string> names;
    const auto add = [&](std::string s) {
        while (!s.empty() && (s.back() == '.' || s.back() == ':' || s.back() == ' ')) s.pop_back();
        if (!s.empty()) names.insert(s);
    };
    std::istringstream in{std::string(md)};
    for (std::string line; std::getline(in, line);) {
        if (!line.empty() && line[0] == '#') {
            const std::size_t i = line.find_first_not_of("# ");
            if (i != std::string::npos) add(line.substr(i));
        }
        for (std::size_t p = line.find("**"); p != std::string::npos;) {
            const std::size_t q = line.find("**", p + 2);
            if (q == std::string::npos) break;
            add(line.substr(p + 2, q - p - 2));
            p = line.find("**", q + 2);
        }
    }
    return names;
}

/// A file the checker reads (see the file comment).
bool scanned(const fs::path& p)
{
    static const std::set<std::string> kExtensions{
        ".h", ".hpp", ".cpp", ".cc", ".in", ".md", ".json", ".cmake", ".sh", ".py"};
    return p.filename() == "CMakeLists.txt" || kExtensions.count(p.extension().string()) > 0;
}

struct Found {
    std::string file; ///< relative to the source root
    Citation citation;
};

std::vector<Found> scanTree(const fs::path& root, int& files)
{
    std::vector<Found> out;
    files = 0;
    fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied), end;
    for (; it != end; ++it) {
        const fs::path& p = it->path();
        if (it->is_directory()) {
            const std::string name = p.filename().string();
            if ((!name.empty() && name[0] == '.') || fs::exists(p / "CMakeCache.txt")) it.disable_recursion_pending();
            continue;
        }
        if (!it->is_regular_file() || !scanned(p)) continue;
        ++files;
        for (const Citation& c : scanText(readFile(p))) out.push_back({fs::relative(p, root).generic_string(), c});
    }
    return out;
}

/// Text written with "$" for the section sign, "PHYS" and "ARCH" for the two
/// page names, so that this file itself cites nothing.
std::string sample(std::string s)
{
    for (std::size_t p; (p = s.find('$')) != std::string::npos;) s.replace(p, 1, kSign);
    for (std::size_t p; (p = s.find("PHYS")) != std::string::npos;) s.replace(p, 4, kPhysics);
    for (std::size_t p; (p = s.find("ARCH")) != std::string::npos;) s.replace(p, 4, kArchitecture);
    return s;
}

std::vector<std::string> ids(const std::vector<Citation>& cs, Citation::Kind kind)
{
    std::vector<std::string> out;
    for (const Citation& c : cs) {
        if (c.kind == kind) out.push_back(c.id);
    }
    return out;
}

using Ids = std::vector<std::string>;

const PhysicsHeadings& physics()
{
    static const PhysicsHeadings h = physicsHeadings(readFile(sourceDir() / "docs" / kPhysics));
    return h;
}

const std::vector<Found>& tree(int* filesOut = nullptr)
{
    static int files = 0;
    static const std::vector<Found> found = scanTree(sourceDir(), files);
    if (filesOut) *filesOut = files;
    return found;
}

// --- The matcher on text written for it -----------------------------------------

TEST(CitationMatcher, FindsSectionsListsAndRanges)
{
    EXPECT_EQ(ids(scanText(sample("see PHYS $1.2 and $5.4")), Citation::Section), (Ids{"1.2", "5.4"}));
    EXPECT_EQ(ids(scanText(sample("(PHYS $1\xE2\x80\x93$4, $6)")), Citation::Section), (Ids{"1", "4", "6"}));
    EXPECT_EQ(ids(scanText(sample("PHYS $5.1/$5.4: fat")), Citation::Section), (Ids{"5.1", "5.4"}));
    EXPECT_EQ(ids(scanText(sample("`docs/PHYS` $7 rely on that")), Citation::Section), (Ids{"7"}));
    // Bare section signs are physics.md's unless another document is named.
    EXPECT_EQ(ids(scanText(sample("the drop (\xC2\xA7"
                                  "3.1 T_f)")),
                  Citation::Section),
        (Ids{"3.1"}));
    EXPECT_EQ(ids(scanText(sample("$3.2 step 2, 0.6 mm")), Citation::Section), (Ids{"3.2"}));
}

TEST(CitationMatcher, FindsNumbersWithoutTheSectionSign)
{
    EXPECT_EQ(ids(scanText(sample("\"PHYS 5.1: fat and muscle\"")), Citation::Section), (Ids{"5.1"}));
    EXPECT_EQ(ids(scanText(sample("PHYS sections 2.1-2.3")), Citation::Section), (Ids{"2.1", "2.3"}));
    EXPECT_EQ(ids(scanText(sample("the bone force (PHYS 4)")), Citation::Section), (Ids{"4"}));
    EXPECT_TRUE(
        ids(scanText(sample("PHYS tags it [chosen]; not in PHYS; PHYS: layer depths")), Citation::Section).empty());
    EXPECT_TRUE(ids(scanText(sample("(PHYS, 2 cases)")), Citation::Section).empty());
}

TEST(CitationMatcher, LeavesOtherDocumentsAlone)
{
    for (const char* text : {"HighBit (PS3.5 $8.1.1): shifted", "one stream (RFC 1952 $2.2)", "magic (RFC 1952 $2.3.1)",
             "PS3.10 $7.1 uses only", "style.md $2, after CHAI3D", "(docs: style.md $6)",
             "Module PS3.3 C.7.6.16 and PS 3.5 $6.2", "see toolchain.md $3.1 and $3.2"}) {
        EXPECT_TRUE(scanText(sample(text)).empty()) << text;
    }
    // The document named before a list owns the whole list; physics.md after it starts its own.
    EXPECT_EQ(ids(scanText(sample("PS3.5 $8.1.1 and PHYS $5.2")), Citation::Section), (Ids{"5.2"}));
}

TEST(CitationMatcher, FollowsCitationsAcrossCommentLines)
{
    const auto cs = scanText(sample("/// lung reaches -910 (PHYS\n/// $5.2), so -950\n"));
    ASSERT_EQ(cs.size(), 1u);
    EXPECT_EQ(cs[0].id, "5.2");
    EXPECT_EQ(cs[0].line, 2);
    EXPECT_TRUE(scanText(sample("// bits of the word (PS3.5\n// $8.1.1): shifted\n")).empty());
}

TEST(CitationMatcher, FindsRegressionCases)
{
    EXPECT_EQ(ids(scanText(sample("slab stack (PHYS $7 R1)")), Citation::Case), (Ids{"1"}));
    EXPECT_EQ(
        ids(scanText(sample("phantoms of PHYS $7: R2 (table),\n/// R3 (Conci), R4\nTEST(R6, X)")), Citation::Case),
        (Ids{"2", "3", "4", "6"}));
    // Relaxation rates and files that do not cite section 7 are not cases.
    EXPECT_EQ(ids(scanText(sample("rate R1 = 1/T1, R2* maps (PHYS $7 R5)")), Citation::Case), (Ids{"5"}));
    EXPECT_TRUE(ids(scanText(sample("R1 and R9 of PHYS $5.1")), Citation::Case).empty());
}

TEST(CitationMatcher, FindsQuotedArchitectureHeadings)
{
    EXPECT_EQ(ids(scanText(sample("(ARCH \"The\n/// force pipeline\", step 2)")), Citation::ArchitectureName),
        (Ids{"The force pipeline"}));
    EXPECT_TRUE(ids(scanText(sample("(docs: ARCH). Reads")), Citation::ArchitectureName).empty());
}

TEST(CitationMatcher, ReadsTheHeadingsOfThePhysicsDocument)
{
    const PhysicsHeadings h = physicsHeadings(sample("# Title\n## 1. Kyung\n### 1.2 Damping\n## $7 Phantoms\n"
                                                     "### The phantoms\n### R1. Slab\n### R12: more\n## 8. References\n"
                                                     "Text 3.4 and R5. are not headings\n"));
    EXPECT_EQ(h.sections, (std::set<std::string>{"1", "1.2", "7", "8"}));
    EXPECT_EQ(h.cases, (std::map<std::string, std::string>{{"1", "7"}, {"12", "7"}}));
}

// --- The tree against docs/ --------------------------------------------------------

TEST(PhysicsDocument, KeepsSectionsOneToEight)
{
    ASSERT_TRUE(fs::exists(sourceDir() / "docs" / kPhysics));
    for (const char* n : {"1", "2", "3", "4", "5", "6", "7", "8"})
        EXPECT_TRUE(physics().sections.count(n)) << "section " << n;
    for (const char* r : {"1", "2", "3", "4", "5", "6", "7"}) {
        ASSERT_TRUE(physics().cases.count(r)) << "case R" << r;
        EXPECT_EQ(physics().cases.at(r), "7") << "case R" << r << " outside section 7";
    }
}

TEST(PhysicsCitations, TheScanReadsTheTree)
{
    int files = 0;
    const auto& found = tree(&files);
    const long sections =
        std::count_if(found.begin(), found.end(), [](const Found& f) { return f.citation.kind == Citation::Section; });
    // The tree cites physics.md about 460 times in some 140 files: far fewer means the walk broke.
    EXPECT_GT(files, 300);
    EXPECT_GT(sections, 300);
}

TEST(PhysicsCitations, EveryCitedSectionHasAHeading)
{
    std::ostringstream missing;
    int n = 0;
    for (const Found& f : tree()) {
        if (f.citation.kind != Citation::Section || physics().sections.count(f.citation.id)) continue;
        missing << "  " << f.file << ":" << f.citation.line << ": " << kPhysics << " " << kSign << f.citation.id
                << "\n";
        ++n;
    }
    EXPECT_EQ(n, 0) << "citations of sections docs/" << kPhysics << " has no heading for:\n" << missing.str();
}

TEST(PhysicsCitations, EveryCitedRegressionCaseExists)
{
    std::ostringstream missing;
    int n = 0;
    for (const Found& f : tree()) {
        if (f.citation.kind != Citation::Case) continue;
        const auto it = physics().cases.find(f.citation.id);
        if (it != physics().cases.end() && it->second == "7") continue;
        missing << "  " << f.file << ":" << f.citation.line << ": R" << f.citation.id << "\n";
        ++n;
    }
    EXPECT_EQ(n, 0) << "regression cases that section 7 of docs/" << kPhysics << " does not have:\n" << missing.str();
}

TEST(ArchitectureCitations, EveryQuotedHeadingExists)
{
    const std::set<std::string> names = architectureNames(readFile(sourceDir() / "docs" / kArchitecture));
    ASSERT_FALSE(names.empty());
    std::ostringstream missing;
    int n = 0;
    for (const Found& f : tree()) {
        if (f.citation.kind != Citation::ArchitectureName || names.count(f.citation.id)) continue;
        missing << "  " << f.file << ":" << f.citation.line << ": " << kArchitecture << " '" << f.citation.id << "'\n";
        ++n;
    }
    EXPECT_EQ(n, 0) << "headings docs/" << kArchitecture << " does not have:\n" << missing.str();
}

} // namespace
