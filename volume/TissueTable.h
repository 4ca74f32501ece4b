// SPDX-License-Identifier: Apache-2.0
/// @file TissueTable.h
/// @brief The tissue table (data/tissues.json): label ids, image values and
/// mechanical parameters, each with unit and source, validated at load.
///
/// Units are converted once, at load, to voxhap's canonical units
/// (architecture.md "Units"): length mm, force N, stiffness N/mm, damping
/// density N·s/mm² (so that force = β·v[mm/s]·ℓ[mm]), T1 in ms, CT in HU.
#pragma once

#include "volume/VolumeMetadata.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace voxhap::volume {

/// @brief A sourced number, already converted to its field's canonical unit.
struct Quantity {
    double value = 0.0;  ///< canonical unit of the field (see the file comment)
    std::string source;  ///< citation, e.g. "[C-ui] skin (physics.md §3.2)"
    bool chosen = false; ///< a default picked for voxhap, not read from a source
};

/// @brief One row of the tissue table.
struct Tissue {
    int id = 0;       ///< label value in the `label` grid
    std::string name; ///< unique snake_case key, e.g. "ligamentum_flavum"
    std::string description;
    std::array<std::uint8_t, 3> colour{}; ///< display colour, sRGB 0..255
    bool critical = false;                ///< default: must not be touched (physics.md §1.1)
    bool rigid = false;                   ///< bone: rendered as contact, not cut (physics.md §1.3)

    double huMin = 0, huTypical = 0, huMax = 0; ///< CT numbers [HU]
    std::string huSource;
    Quantity t1At1p5T; ///< T1 at 1.5 T [ms]
    Quantity t1At3T;   ///< T1 at 3 T [ms]

    // Mechanical parameters; absent where no model needs them (e.g. lung).
    std::optional<Quantity> thickness;       ///< default layer thickness [mm]
    std::optional<Quantity> punctureForce;   ///< force at puncture [N] (physics.md §3.2)
    std::optional<Quantity> cuttingForce;    ///< cutting force while advancing [N] (§2.3)
    std::optional<Quantity> elasticity;      ///< tip stiffness k [N/mm] (§4)
    std::optional<Quantity> frictionViscous; ///< shaft viscous friction b [N·s/mm²] (§4)
    std::optional<Quantity> frictionCoulomb; ///< Coulomb friction C [N] (§4)
    std::optional<Quantity> damping;         ///< damping density β [N·s/mm²] (§1.2, §5.4)
    /// Winkler modulus k holding a bending needle [N/mm²] (physics.md §9.2).
    std::optional<Quantity> foundationModulus;

    /// @brief T1 at the given field strength [ms].
    double t1(FieldStrength f) const { return f == FieldStrength::T3 ? t1At3T.value : t1At1p5T.value; }
};

/// @brief The validated tissue table.
///
/// Loading rejects, with one message naming the file, the tissue and the
/// field: unknown keys, missing units or sources, units of the wrong kind,
/// negative or non-finite values, duplicate ids or names, and a table without
/// air at id 0.
/// @note Immutable after construction; safe to share between threads.
class TissueTable {
public:
    /// @brief Read and validate a tissue table file. @throw IoError, ValueError
    static TissueTable load(const std::filesystem::path& file);
    /// @brief Validate JSON text; @p origin names it in error messages.
    static TissueTable parse(std::string_view json, const std::string& origin);
    /// @brief The table compiled into voxhap from data/tissues.json.
    static const TissueTable& builtin();

    const std::vector<Tissue>& tissues() const { return mTissues; }
    /// @brief The tissue with this id, or nullptr.
    const Tissue* find(int id) const;
    /// @brief The tissue with this name, or nullptr.
    const Tissue* find(std::string_view name) const;
    /// @brief The tissue with this id. @throw ValueError naming the id
    const Tissue& at(int id) const;
    /// @brief The tissue with this name. @throw ValueError listing the known names
    const Tissue& at(std::string_view name) const;
    /// @brief Largest id in the table (for lookup arrays indexed by label).
    int maxId() const { return mMaxId; }
    /// @brief Where the table came from (file name or "builtin").
    const std::string& origin() const { return mOrigin; }

private:
    std::vector<Tissue> mTissues;
    std::vector<int> mIndexById; // id -> index into mTissues, -1 where unused
    int mMaxId = 0;
    std::string mOrigin;
};

} // namespace voxhap::volume
