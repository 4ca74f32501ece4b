// SPDX-License-Identifier: Apache-2.0
/// @file Phantom.h
/// @brief Test fixtures: analytic phantoms with a damping grid whose values the
/// test chooses (so that expected integrals never come from the code under test).
#pragma once

#include "haptic/materials/MaterialField.h"
#include "phantoms/Phantoms.h"
#include "volume/Grids.h"

#include <map>
#include <memory>
#include <string>

namespace voxhap::test {

/// Damping densities used in tests [N·s/mm²]: physics.md §5.4 fitted values
/// (β_fat 3696, β_muscle 8152 N·s/m²) and twice β_muscle for the ligaments.
inline const std::map<std::string, double>& testBeta()
{
    static const std::map<std::string, double> kBeta{{"skin", 8152e-6}, {"fat", 3696e-6}, {"muscle", 8152e-6},
        {"interspinous_ligament", 16304e-6}, {"ligamentum_flavum", 16304e-6}};
    return kBeta;
}

/// A β grid over the label grid's active voxels: β = beta[name of label], 0 for unlisted tissues.
inline volume::FloatGrid::Ptr betaFromLabels(const volume::LabelGrid& labels, const std::map<std::string, double>& beta)
{
    const auto& table = volume::TissueTable::builtin();
    auto grid = volume::FloatGrid::create(0.0f);
    grid->setTree(std::make_shared<volume::FloatGrid::TreeType>(labels.tree(), 0.0f, openvdb::TopologyCopy()));
    auto acc = labels.getConstAccessor();
    for (auto it = grid->tree().beginValueOn(); it; ++it) {
        const auto found = beta.find(table.at(acc.getValue(it.getCoord())).name);
        it.setValue(found == beta.end() ? 0.0f : float(found->second));
    }
    grid->setTransform(labels.transform().copy());
    return grid;
}

/// A phantom volume and a material field whose β comes from testBeta().
struct FieldFixture {
    std::unique_ptr<volume::Volume> volume;
    std::unique_ptr<haptic::MaterialField> field;
};

inline FieldFixture makeFieldFixture(const volume::PhantomModel& model, const volume::GridSpec& grid)
{
    const auto& table = volume::TissueTable::builtin();
    FieldFixture f;
    f.volume = std::make_unique<volume::Volume>(volume::makePhantom(model, grid, table));
    const auto labels = volume::labelGrid(*f.volume);
    f.field = std::make_unique<haptic::MaterialField>(betaFromLabels(*labels, testBeta()), labels, table);
    return f;
}

} // namespace voxhap::test
