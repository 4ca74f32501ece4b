// SPDX-License-Identifier: Apache-2.0
/// @file Viewer.h
/// @brief The interactive planning viewer (`voxhap view`): four panes (axial,
/// sagittal, coronal, 3D) of one volume, clicks that set the entry and target
/// or measure distances and angles (PlanEditor), and a live needle.
///
/// The viewer is a state plus a renderer of the whole window into one Image;
/// it knows nothing of X events or sockets, so that a script of synthetic
/// events drives it exactly as a mouse does (ViewerScript.h), and a test can
/// check the picture. Slices are drawn in software (SliceView); the 3D pane is
/// a VolumeView3d rendered once (seconds on a CT in software GL) with the
/// paths and the live needle drawn over it in software, so that a moving
/// needle redraws in milliseconds.
///
/// Controls (keys are X keysym names):
/// - n, p, d, a: tools navigate, plan (entry then target), distance, angle
/// - left click: use the tool at that point of a slice
/// - Up / Page_Up, Down / Page_Down, wheel: next or previous slice of the pane
///   last clicked (one finest-voxel step along the pane's normal)
/// - w: next window (soft tissue, bone, lung) on CT; MR keeps the body's own
///   range (RenderVolume::defaultWindow) and says so; c: clear measurements
/// - s: save the plan (voxhap-plan/1); q or Escape: quit
/// - 3D pane (OrbitCamera.h, VTK's trackball camera semantics): left drag
///   rotates, the wheel zooms, r resets the camera. While the camera moves the
///   pane is drawn at RenderQuality::Moving; at full quality once the drag
///   ends (button released) or kSettleS after the last wheel step (settle()).
#pragma once

#include "render/raster/Image.h"
#include "render/viewer/OrbitCamera.h"
#include "render/viewer/PlanEditor.h"
#include "render/viewer/ViewerLayout.h"
#include "render/views/ViewFrame.h"
#include "render/views/ViewTypes.h"
#include "render/volume3d/VolumeView3d.h"

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace voxhap::volume {
class TissueTable;
class Volume;
} // namespace voxhap::volume

namespace voxhap::render {

class RenderVolume;

/// @brief Quiet time after the last wheel step before the 3D pane is redrawn at
/// full quality [s] [chosen]: longer than the gap between the notches of a
/// spun wheel (tens of ms), short against the 1.5 s the issue allows.
inline constexpr double kSettleS = 0.3;

struct ViewerOptions {
    int width = 1024, height = 1048;    ///< window [px], status bar included
    BlendMode mode = BlendMode::Colour; ///< of the 3D pane
    RayCaster caster = RayCaster::Auto;
    MovingPath moving = MovingPath::Subsample; ///< the 3D pane while its camera moves
    int movingFactor = 3;                      ///< View3dStyle::movingFactor
    /// View3dStyle::sampleVoxels of the 3D pane's full-quality frame. 1.75 voxels:
    /// on the shared CT and the torso phantom the still frame stays within about
    /// 2 grey levels (mean) of one-voxel steps and arrives within 1.5 s of
    /// stopping on 2 cores with a margin (CT: 1.2 s), where one-voxel steps took
    /// 1.6–2.7 s and 1.5 voxels 1.4–1.6 s (`voxhap bench render`,
    /// docs/reference.md "Views and plots").
    double sampleVoxels = 1.75;
    std::optional<WindowLevel> window; ///< slices and 3D; default RenderVolume::defaultWindow (CT presets on CT only)
    bool labels = true;                ///< tissue colours on the slices
    bool threeD = true;                ///< false: the 3D pane says why not (threeDNote) instead
    std::string threeDNote;            ///< shown in the 3D pane when threeD is false
    std::optional<Vec3d> point;        ///< first crosshair [mm, LPS]; default the first target, else the centre
    planning::Plan plan;               ///< paths loaded with the volume
    std::filesystem::path planOut = "plan.json"; ///< where key s saves
};

/// @brief One input event, from the window or a script.
struct ViewerEvent {
    enum class Kind {
        Click,
        Key,
        Scroll,
        Drag,   ///< the left button held and moved (3D pane: rotate)
        Release ///< the left button released (3D pane: the drag ends, full quality)
    };
    Kind kind = Kind::Key;
    ViewKind pane = ViewKind::Axial; ///< Click, Scroll, Drag
    Vec2d px{0, 0};                  ///< Click: in the pane image's pixels; Drag: the motion [px, y down]
    std::string key;                 ///< Key: keysym name
    int steps = 0;                   ///< Scroll: slices, positive along the pane's normal
};

class Viewer {
public:
    /// @throw ValueError on a volume without image values or a window too small
    Viewer(const volume::Volume& v, const ViewerOptions& options, const volume::TissueTable& table);
    ~Viewer();
    Viewer(const Viewer&) = delete;
    Viewer& operator=(const Viewer&) = delete;

    /// @brief Apply one event. @return false once the event asks to quit
    bool handle(const ViewerEvent& e);
    /// @brief A click at window pixel (@p x, @p y): the pane under it, if any.
    bool clickWindow(int x, int y);
    /// @brief Scroll in the pane under window pixel (@p x, @p y).
    void scrollWindow(int x, int y, int steps);
    /// @brief The pointer moved to window pixel (@p x, @p y) with the left button
    /// held: a drag if the button went down in the 3D pane.
    void dragWindow(int x, int y);
    /// @brief The left button went up.
    void releaseWindow();
    /// @brief Call when idle: once the camera has been still for kSettleS after a
    /// wheel step (or the drag ended), the 3D pane is marked for a full-quality
    /// redraw. @return true if it was
    bool settle(std::chrono::steady_clock::time_point now = std::chrono::steady_clock::now());
    /// @brief True while the 3D pane draws at moving quality (a drag or the settle time).
    bool moving() const { return mMoving; }
    /// @brief The 3D pane's camera.
    const OrbitCamera& camera() const { return mCamera; }
    /// @brief The quality of the 3D pane's last rendering (Full before any).
    RenderQuality last3dQuality() const { return m3dQuality; }

    /// @brief The live needle (nullopt: none).
    void setNeedle(const std::optional<planning::NeedlePose>& needle);
    /// @brief A note for the status bar (e.g. the pose stream's state).
    void setNote(std::string note);
    /// @brief Redraw every pane at the next render(), the 3D one included (for benchmarks).
    void invalidate();
    /// @brief True if something changed since the last render().
    bool dirty() const { return mDirty; }

    /// @brief The whole window: the four panes and the status bar.
    Image render();

    const ViewerLayout& layout() const { return mLayout; }
    /// @brief The pixel frame of a pane (slices follow the crosshair; 3D is fixed).
    /// All panes share one pixel size: the smallest at which every view fits its pane.
    const ViewFrame& frame(ViewKind v) const { return mFrames[std::size_t(v)]; }
    /// @brief Where a pane's image starts in the window [px].
    Vec2d imageOrigin(ViewKind v) const;
    const Vec3d& point() const { return mPoint; }
    const PlanEditor& editor() const { return mEditor; }
    std::string status() const;
    /// @brief The status line of the last action ("saved plan.json", "nothing to save").
    const std::string& lastMessage() const { return mMessage; }
    /// @brief Why the last save failed (it names the file); empty if it did not.
    const std::string& saveError() const { return mSaveError; }

private:
    void updateFrames();
    void savePlan();
    Image renderSlicePane(ViewKind v);
    Image render3dPane();
    void drawOver3d(Image& img) const;
    void cameraMoved(bool dragging);

    ViewerOptions mOpt;
    const volume::TissueTable& mTable;
    std::unique_ptr<RenderVolume> mVolume;
    ViewerLayout mLayout;
    WorldBounds mBox;
    double mPixelMm = 1.0, mStepMm = 1.0;
    Vec3d mPoint{0, 0, 0};
    std::array<ViewFrame, 4> mFrames;
    std::array<Image, 3> mSliceBase; ///< slices without overlays, until the crosshair or window moves
    std::array<bool, 3> mSliceStale{true, true, true};
    Image m3dImage; ///< the volume alone; paths and needle go over a copy
    bool m3dStale = true, mDirty = true;
    std::unique_ptr<VolumeView3d> m3d;
    OrbitCamera mCamera;
    bool mMoving = false, mDragging = false;
    RenderQuality m3dQuality = RenderQuality::Full;
    std::chrono::steady_clock::time_point mSettleAt;
    std::optional<Vec2d> mDragFrom; ///< window pixel where the last 3D drag step ended
    WindowLevel mWindow;
    int mWindowPreset = 0;
    ViewKind mActive = ViewKind::Axial;
    PlanEditor mEditor;
    std::optional<planning::NeedlePose> mNeedle;
    std::string mNote, mMessage, mSaveError;
};

} // namespace voxhap::render
