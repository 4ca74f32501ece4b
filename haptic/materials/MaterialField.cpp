// SPDX-License-Identifier: Apache-2.0
/// @file MaterialField.cpp
/// @brief Building the property grids: β from T1 or per label (physics.md §1.2,
/// §5.4) and device-limited bone stiffness from HU (§1.3, §5.3).

#include "haptic/materials/MaterialField.h"

#include "core/Errors.h"
#include "haptic/materials/FieldGrids.h"

#include <openvdb/tools/Count.h> // for minMax
#include <openvdb/tree/LeafManager.h>
#include <tbb/enumerable_thread_specific.h>

#include <cmath>
#include <sstream>

namespace voxhap::haptic {

namespace {

using namespace voxhap::volume;

/// The bone threshold without labels: about 150 HU (physics.md §5.2 [chosen]).
constexpr double kBoneHuThreshold = 150.0;

/// The field strength of the T1 law (MaterialOptions::field), or nothing when
/// the metadata record a field that has no law.
std::optional<FieldStrength> fieldOf(const Volume& v, const MaterialOptions& o)
{
    if (o.field) return *o.field;
    const VolumeMetadata& md = v.metadata();
    if (md.fieldStrength) return *md.fieldStrength;
    if (md.fieldStrengthTesla) return std::nullopt;
    return FieldStrength::T1_5;
}

/// Why T1 cannot be read for a field without a law, for messages.
std::string noLawReason(const VolumeMetadata& md)
{
    std::ostringstream s;
    s << "the MR's field strength (" << md.fieldStrengthTesla.value_or(0.0) << " T, from the "
      << factSourceName(md.fieldStrengthSource)
      << ") is neither 1.5 T nor 3 T, the fields the T1 damping law is fitted at (physics.md §5.4)";
    return s.str();
}

void checkLabelRange(const LabelGrid& labels)
{
    if (labels.activeVoxelCount() == 0) return;
    const auto mm = openvdb::tools::minMax(labels.tree());
    if (mm.min() < 0 || mm.max() >= kMaxLabels) {
        throw ValueError("label grid: tissue ids must be within 0.." + std::to_string(kMaxLabels - 1) + ", found " +
            std::to_string(mm.min()) + ".." + std::to_string(mm.max()));
    }
}

/// Per voxel (or uniform tile): β from the label's rule.
struct BetaRule {
    const std::array<LabelMaterial, kMaxLabels>* perLabel;
    std::array<bool, kMaxLabels> fromT1{}; // §5.4: Eq. 4 only for fat and muscle
    T1DampingLaw law;
    bool haveLabels = false, haveT1 = false;

    bool usesT1(int label) const { return haveT1 && (!haveLabels || fromT1[std::size_t(label)]); }
    /// @param t1 the voxel's T1, or nothing where the t1 grid is inactive: outside
    ///        the MR's field of view or body in a fused volume (§5.5), where the
    ///        table's value by label stands in
    float operator()(int label, std::optional<float> t1) const
    {
        if (t1 && usesT1(label)) return float(law.dampingNsPerMm2(*t1));
        const double b = (*perLabel)[std::size_t(label)].dampingNsPerMm2;
        return std::isfinite(b) ? float(b) : 0.0f;
    }
};

/// The label and T1 grids read through one accessor pair (one per thread).
struct SourceReader {
    SourceReader(const LabelGrid* l, const FloatGrid* t)
        : labelAcc(l ? std::optional(l->getConstAccessor()) : std::nullopt),
          t1Acc(t ? std::optional(t->getConstAccessor()) : std::nullopt)
    {
    }
    int label(const openvdb::Coord& c) { return labelAcc ? labelAcc->getValue(c) : 1; }
    /// T1 where the t1 grid is active; nothing elsewhere (and without a t1 grid).
    std::optional<float> t1(const openvdb::Coord& c)
    {
        float v = 0.0f;
        if (t1Acc && t1Acc->probeValue(c, v)) return v;
        return std::nullopt;
    }

    std::optional<LabelGrid::ConstAccessor> labelAcc;
    std::optional<FloatGrid::ConstAccessor> t1Acc;
};

/// β over every leaf, in parallel: each leaf is written by one task only.
/// (A threaded tools::foreach over the tree's ValueOn iterator, tiles and
/// voxels together, gave wrong voxels now and then on a loaded machine.)
void fillLeaves(FloatGrid::TreeType& tree, const BetaRule& rule, const LabelGrid* labels, const FloatGrid* t1)
{
    tbb::enumerable_thread_specific<SourceReader> readers([&] { return SourceReader(labels, t1); });
    openvdb::tree::LeafManager<FloatGrid::TreeType> leaves(tree);
    leaves.foreach ([&](FloatGrid::TreeType::LeafNodeType& leaf, std::size_t) {
        SourceReader& r = readers.local();
        for (auto it = leaf.beginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            it.setValue(rule(r.label(c), r.t1(c)));
        }
    });
}

/// How many of the β grid's voxels took T1 and how many the table (after the
/// fill: every tile left is uniform in label and in T1's presence).
DampingSources countSources(
    const FloatGrid::TreeType& tree, const BetaRule& rule, const LabelGrid* labels, const FloatGrid* t1)
{
    DampingSources out;
    auto fromT1 = [&](SourceReader& r, const openvdb::Coord& c) { return rule.usesT1(r.label(c)) && r.t1(c); };
    {
        SourceReader r(labels, t1);
        auto it = tree.cbeginValueOn();
        it.setMaxDepth(FloatGrid::TreeType::ValueOnCIter::LEAF_DEPTH - 1);
        for (; it; ++it) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            (fromT1(r, it.getCoord()) ? out.fromT1Voxels : out.fromTableVoxels) += std::int64_t(box.volume());
        }
    }
    tbb::enumerable_thread_specific<SourceReader> readers([&] { return SourceReader(labels, t1); });
    tbb::enumerable_thread_specific<DampingSources> counts;
    openvdb::tree::LeafManager<const FloatGrid::TreeType> leaves(tree);
    leaves.foreach ([&](const FloatGrid::TreeType::LeafNodeType& leaf, std::size_t) {
        SourceReader& r = readers.local();
        DampingSources& c = counts.local();
        for (auto it = leaf.cbeginValueOn(); it; ++it)
            ++(fromT1(r, it.getCoord()) ? c.fromT1Voxels : c.fromTableVoxels);
    });
    for (const DampingSources& c : counts) {
        out.fromT1Voxels += c.fromT1Voxels;
        out.fromTableVoxels += c.fromTableVoxels;
    }
    return out;
}

FloatGrid::Ptr buildDamping(const Volume& v, const BetaRule& rule, DampingSources& sources)
{
    const auto labels = labelGrid(v);
    const auto t1 = t1Grid(v);
    auto tree = labels ? std::make_shared<FloatGrid::TreeType>(labels->tree(), 0.0f, openvdb::TopologyCopy())
                       : std::make_shared<FloatGrid::TreeType>(t1->tree(), 0.0f, openvdb::TopologyCopy());
    // Tiles (uniform label regions, few): serially. A tile whose T1 varies
    // inside it (the T1 tree has a child node there; both trees share the
    // node layout) is made voxels and filled with the leaves.
    bool nonUniform = false;
    {
        SourceReader r(labels.get(), t1.get());
        auto it = tree->beginValueOn();
        it.setMaxDepth(FloatGrid::TreeType::ValueOnIter::LEAF_DEPTH - 1);
        for (; it; ++it) {
            const openvdb::Coord c = it.getCoord();
            const int label = r.label(c);
            if (rule.usesT1(label) && r.t1Acc && r.t1Acc->getValueDepth(c) > int(it.getDepth())) {
                nonUniform = true;
                continue;
            }
            it.setValue(rule(label, r.t1(c)));
        }
    }
    if (nonUniform) tree->voxelizeActiveTiles(); // rare; tiles already filled become equal voxels
    fillLeaves(*tree, rule, labels.get(), t1.get());
    sources = countSources(*tree, rule, labels.get(), t1.get());
    tree->prune(); // exact: tolerance 0
    auto grid = FloatGrid::create(tree);
    grid->setTransform(v.transform().copy());
    return grid;
}

} // namespace

MaterialField::MaterialField(const Volume& v, const TissueTable& table, const MaterialOptions& options)
{
    initializeOpenVdb();
    fillPerLabel(table);
    const std::optional<FieldStrength> field = fieldOf(v, options);
    mLaw = t1DampingLaw(field.value_or(FieldStrength::T1_5));
    const auto labels = labelGrid(v);
    if (labels) {
        checkLabelRange(*labels);
        mLabels = labels;
    }

    if (options.needs.damping) {
        if (!labels && !v.has(Channel::T1)) {
            if (v.has(Channel::Intensity)) {
                // MR that is not T1 (MrMaterial.h): never read as T1 silently.
                const std::string w(mrWeightingName(v.metadata().mrWeighting.value_or(MrWeightingKind::Unknown)));
                throw ValueError("material field: tissue damping needs T1 or tissue labels, and this MR (" + w +
                    ") is an intensity grid, not T1: segment it (voxhap segment), or load a T1-weighted "
                    "image with --t1-weighted or a T1 map with --t1-map");
            }
            throw ValueError("material field: tissue damping needs a label or t1 grid (segment the volume first)");
        }
        const bool t1 = v.has(Channel::T1) && v.metadata().t1Units == "ms";
        if (t1 && !field && !labels) {
            throw ValueError("material field: tissue damping needs T1 with a law or tissue labels, and " +
                noLawReason(v.metadata()) + ": segment it (labels carry the tissue's damping)");
        }
        BetaRule rule;
        rule.perLabel = &mPerLabel;
        rule.law = mLaw;
        rule.haveLabels = labels != nullptr;
        rule.haveT1 = t1 && field; // without a law, fat and muscle take the table's β as every other label
        for (const char* name : {"fat", "muscle"}) {
            if (const Tissue* t = table.find(name); t && t->id < kMaxLabels) rule.fromT1[std::size_t(t->id)] = true;
        }
        auto beta = buildDamping(v, rule, mSources);
        mMaxBeta = beta->activeVoxelCount() ? double(openvdb::tools::minMax(beta->tree()).max()) : 0.0;
        mBeta = beta;
    }

    if (options.needs.boneStiffness) {
        const auto hu = huGrid(v);
        if (!hu) throw ValueError("material field: bone stiffness needs an hu grid (a CT volume)");
        const Geometry g = v.geometry();
        const double lc = g.spacing.minCoeff(); // L_c = one voxel (physics.md §1.3 [chosen])
        const double limit = options.device.maxStiffnessNPerMm;
        auto k = FloatGrid::create(0.0f);
        auto kAcc = k->getAccessor();
        auto labelAcc = labels ? std::optional(labels->getConstAccessor()) : std::nullopt;
        StiffnessReport& r = mStiffnessReport;
        r.deviceLimitNPerMm = limit;
        double sum = 0.0;
        // Voxel by voxel over the active HU region (bone is a small part of a scan).
        for (auto it = hu->cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto c = box.begin(); c; ++c) {
                const float huValue = *it;
                const bool bone = labelAcc
                    ? mPerLabel[std::size_t(std::clamp(labelAcc->getValue(*c), 0, kMaxLabels - 1))].rigid
                    : double(huValue) >= kBoneHuThreshold;
                if (!bone) continue;
                const double e = youngsModulusMPa(options.modulusLaw, densityFromHu(huValue));
                const double computed = contactStiffnessNPerMm(e, options.tipAreaMm2, lc);
                const double rendered = std::min(computed, limit);
                kAcc.setValueOn(*c, float(rendered));
                ++r.boneVoxels;
                sum += computed;
                r.computedMaxNPerMm = std::max(r.computedMaxNPerMm, computed);
                r.renderedMaxNPerMm = std::max(r.renderedMaxNPerMm, rendered);
            }
        }
        if (r.boneVoxels) r.computedMeanNPerMm = sum / double(r.boneVoxels);
        k->tree().prune();
        k->setTransform(v.transform().copy());
        mStiffness = k;
    }
}

MaterialField::MaterialField(GridConstPtr beta, GridConstPtr labels, const TissueTable& table)
    : mBeta(std::move(beta)), mLabels(std::move(labels))
{
    initializeOpenVdb();
    fillPerLabel(table);
    if (mBeta && !openvdb::gridConstPtrCast<FloatGrid>(mBeta))
        throw ValueError("material field: damping grid must be float");
    if (mLabels) {
        auto l = openvdb::gridConstPtrCast<LabelGrid>(mLabels);
        if (!l) throw ValueError("material field: label grid must be int32");
        checkLabelRange(*l);
    }
    if (auto b = openvdb::gridConstPtrCast<FloatGrid>(mBeta); b && b->activeVoxelCount()) {
        mMaxBeta = double(openvdb::tools::minMax(b->tree()).max());
    }
}

void MaterialField::fillPerLabel(const TissueTable& table)
{
    for (const Tissue& t : table.tissues()) {
        if (t.id >= kMaxLabels) {
            throw ValueError(table.origin() + ": tissue '" + t.name + "' id " + std::to_string(t.id) +
                " exceeds the force path's limit of " + std::to_string(kMaxLabels - 1));
        }
        LabelMaterial& m = mPerLabel[std::size_t(t.id)];
        const auto value = [](const std::optional<Quantity>& q) { return q ? q->value : 0.0; };
        m.present = true;
        m.critical = t.critical;
        m.rigid = t.rigid;
        m.dampingNsPerMm2 = value(t.damping);
        m.punctureForceN = value(t.punctureForce);
        m.cuttingForceN = value(t.cuttingForce);
        m.elasticityNPerMm = value(t.elasticity);
        m.frictionViscousNsPerMm2 = value(t.frictionViscous);
        m.frictionCoulombN = value(t.frictionCoulomb);
        m.foundationNPerMm2 = value(t.foundationModulus);
    }
}

} // namespace voxhap::haptic
