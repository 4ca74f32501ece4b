// SPDX-License-Identifier: Apache-2.0
/// @file PlanEditor.cpp
#include "render/viewer/PlanEditor.h"

#include <iomanip>
#include <sstream>

namespace voxhap::render {

std::string_view toolName(Tool t)
{
    switch (t) {
    case Tool::Navigate:
        return "navigate";
    case Tool::Plan:
        return "plan";
    case Tool::Distance:
        return "distance";
    case Tool::Angle:
        return "angle";
    }
    return "?";
}

PlanEditor::PlanEditor(planning::Plan initial) : mPlan(std::move(initial)) { }

void PlanEditor::setTool(Tool t)
{
    if (t == mTool) return;
    mTool = t;
    mPoints.clear(); // a half-picked measurement does not carry over to another tool
}

void PlanEditor::clearMeasurements()
{
    mPoints.clear();
    mDistance.reset();
    mAngle.reset();
    mPendingEntry.reset();
}

std::optional<Vec3d> PlanEditor::click(const Vec3d& w)
{
    switch (mTool) {
    case Tool::Navigate:
        return w;
    case Tool::Plan:
        if (!mPendingEntry) {
            mPendingEntry = w;
            return std::nullopt;
        }
        if ((w - *mPendingEntry).norm() == 0.0)
            return std::nullopt; // a path needs a direction: wait for another target
        {
            planning::PlannedPath p;
            p.name = "viewer";
            p.entry = *mPendingEntry;
            p.target = w;
            if (mEdited) {
                mPlan.paths[*mEdited] = p;
            } else {
                mEdited = mPlan.paths.size();
                mPlan.paths.push_back(p);
            }
        }
        mPendingEntry.reset();
        return std::nullopt;
    case Tool::Distance:
        mPoints.push_back(w);
        if (mPoints.size() == 2) {
            mDistance = Segment{mPoints[0], mPoints[1]};
            mPoints.clear();
        }
        return std::nullopt;
    case Tool::Angle:
        mPoints.push_back(w);
        if (mPoints.size() == 4) {
            mAngle = std::make_pair(Segment{mPoints[0], mPoints[1]}, Segment{mPoints[2], mPoints[3]});
            mPoints.clear();
        }
        return std::nullopt;
    }
    return std::nullopt;
}

std::string PlanEditor::status() const
{
    std::ostringstream os;
    os << std::fixed << std::setprecision(1) << "tool " << toolName(mTool);
    switch (mTool) {
    case Tool::Navigate:
        os << ": click to move the slices";
        break;
    case Tool::Plan:
        os << (mPendingEntry ? ": click the target" : ": click the entry");
        break;
    case Tool::Distance:
        os << ": click point " << mPoints.size() + 1 << " of 2";
        break;
    case Tool::Angle:
        os << ": click point " << mPoints.size() + 1 << " of 4";
        break;
    }
    if (mEdited) {
        const planning::PlannedPath& p = mPlan.paths[*mEdited];
        os << " | path " << distanceMm(p.entry, p.target) << " mm";
    }
    if (mDistance) os << " | distance " << mDistance->lengthMm() << " mm";
    if (mAngle) {
        if (const auto a = angleDeg(mAngle->first, mAngle->second)) os << " | angle " << *a << " deg";
    }
    return os.str();
}

} // namespace voxhap::render
