// SPDX-License-Identifier: Apache-2.0
/// @file Volume.h
/// @brief A patient or phantom volume: named sparse grids (hu, t1, label)
/// sharing one index-to-world transform, plus metadata.
///
/// World space is patient LPS in millimetres; a voxel's index coordinate
/// (i, j, k) is its centre (the DICOM and OpenVDB convention). Typed access
/// to the grids lives in volume/Grids.h, which brings in the OpenVDB headers;
/// this header stays light so that command-line glue compiles quickly.
#pragma once

#include "core/Math.h"
#include "volume/VolumeMetadata.h"

#include <openvdb/math/Transform.h>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace openvdb {
OPENVDB_USE_VERSION_NAMESPACE
namespace OPENVDB_VERSION_NAME {
class GridBase;
}
} // namespace openvdb

namespace voxhap::volume {

/// @brief The grids a Volume may hold.
///
/// `t1` holds T1 in milliseconds and nothing else: a T1 map, or a T1-weighted
/// scan normalised per scan (T1Normalisation.h). Every other MR image (PD, T2,
/// FLAIR, diffusion, field maps, phase, T1-weighted scans that could not be
/// normalised, MR of unknown weighting) is an `intensity` grid, which no force
/// law reads as T1; metadata().mrWeighting says what it is (VolumeMetadata.h).
enum class Channel {
    Hu,        ///< float, CT Hounsfield units
    T1,        ///< float, MR T1 [ms]
    Label,     ///< int32, tissue id from data/tissues.json
    Intensity, ///< float, MR signal intensity [arbitrary units], never T1
};
inline constexpr std::array<Channel, 4> kChannels{Channel::Hu, Channel::T1, Channel::Label, Channel::Intensity};

/// @brief The grid name of a channel in .vdb files: "hu", "t1" or "label".
std::string_view channelName(Channel c);

/// @name Inactive background of every grid: air.
/// @{
inline constexpr float kAirHu = -1000.0f;
inline constexpr float kAirT1 = 0.0f;
inline constexpr float kAirIntensity = 0.0f;
inline constexpr std::int32_t kAirLabel = 0;
/// @}

/// @brief The dense extent of a volume in index space, bounds inclusive.
struct IndexBox {
    Vec3i min{0, 0, 0};
    Vec3i max{-1, -1, -1};

    bool empty() const { return (max.array() < min.array()).any(); }
    Vec3i dims() const { return empty() ? Vec3i::Zero() : Vec3i(max - min + Vec3i::Ones()); }
    std::int64_t voxelCount() const
    {
        const Vec3i d = dims();
        return std::int64_t(d.x()) * d.y() * d.z();
    }
    bool operator==(const IndexBox&) const = default;
};

/// @brief Spacing, origin and direction cosines of an index-to-world affine map:
/// world = origin + direction · diag(spacing) · ijk.
struct Geometry {
    Vec3d spacing{1.0, 1.0, 1.0};        ///< voxel size along index i, j, k [mm]
    Vec3d origin{0.0, 0.0, 0.0};         ///< world position of voxel (0,0,0)'s centre [mm, LPS]
    Mat3d direction = Mat3d::Identity(); ///< columns: unit world directions of the i, j, k axes
};

/// @brief Build an OpenVDB linear transform from a Geometry.
/// @throw ValueError if a spacing is not positive and finite or the direction
///        matrix is singular or not unit-column.
openvdb::math::Transform::Ptr makeTransform(const Geometry& g);

/// @brief Recover spacing, origin and direction from a linear transform.
/// @throw ValueError if the transform is not linear (e.g. a frustum).
Geometry geometryOf(const openvdb::math::Transform& xform);

/// @brief Named sparse grids sharing one transform, with metadata.
///
/// Any subset of the channels may be present. Setting a grid gives it the
/// volume's transform and its channel's name, after checking its value type
/// and background. Grids are shared read-only once set.
/// @note Not thread-safe to modify; concurrent const access is safe.
class Volume {
public:
    using GridPtr = std::shared_ptr<openvdb::GridBase>;
    using GridConstPtr = std::shared_ptr<const openvdb::GridBase>;

    /// @param xform the index-to-world transform every grid will share
    /// @param box   the dense extent in index space (what a dense array would hold)
    Volume(openvdb::math::Transform::Ptr xform, const IndexBox& box);
    /// @brief Convenience: a transform made from @p g.
    Volume(const Geometry& g, const IndexBox& box);

    const openvdb::math::Transform& transform() const { return *mTransform; }
    openvdb::math::Transform::ConstPtr transformPtr() const { return mTransform; }
    Geometry geometry() const { return geometryOf(*mTransform); }
    const IndexBox& indexBox() const { return mBox; }

    /// @brief World (LPS mm) position of an index-space point (voxel centres at integers).
    Vec3d indexToWorld(const Vec3d& ijk) const;
    /// @brief Index-space position of a world (LPS mm) point.
    Vec3d worldToIndex(const Vec3d& xyz) const;
    /// @brief Axis-aligned world bounding box of the dense extent, voxel faces included [mm].
    std::array<Vec3d, 2> worldBounds() const;

    bool has(Channel c) const { return mGrids[index(c)] != nullptr; }
    /// @brief The grid of a channel, or nullptr if absent.
    GridConstPtr grid(Channel c) const { return mGrids[index(c)]; }
    /// @brief Store a grid: FloatGrid for Hu and T1, Int32Grid for Label, with
    /// the air background. @throw ValueError on the wrong type or background.
    void setGrid(Channel c, GridPtr grid);
    void removeGrid(Channel c) { mGrids[index(c)].reset(); }

    /// @name Derived grids: FloatGrids computed from the channels and saved with
    /// them, e.g. the signed distance field "sdf.kidney" of a critical structure
    /// (segmentation/DistanceField.h). They share the volume's transform.
    /// @{
    /// @brief Store a derived FloatGrid under @p name (not hu, t1 or label; replaces
    /// one of the same name). @throw ValueError on a reserved name or a non-float grid
    void setDerived(const std::string& name, GridPtr grid);
    /// @brief The derived grid @p name, or nullptr.
    GridConstPtr derived(const std::string& name) const;
    /// @brief All derived grids, by name.
    const std::map<std::string, GridPtr>& derivedGrids() const { return mDerived; }
    void removeDerived(const std::string& name) { mDerived.erase(name); }
    /// @}

    VolumeMetadata& metadata() { return mMeta; }
    const VolumeMetadata& metadata() const { return mMeta; }

private:
    static std::size_t index(Channel c) { return static_cast<std::size_t>(c); }

    openvdb::math::Transform::Ptr mTransform;
    IndexBox mBox;
    std::array<GridPtr, kChannels.size()> mGrids{};
    std::map<std::string, GridPtr> mDerived;
    VolumeMetadata mMeta;
};

} // namespace voxhap::volume
