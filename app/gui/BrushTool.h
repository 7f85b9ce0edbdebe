// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The app's brush (engine BrushSettings plus the surface-relative depth and the tablet
/// pressure mapping) and the QUndoCommand that wraps one stroke of the engine's History
/// (lucent/material/History.h).
///
/// Edits are applied by the engine when the user paints; pushing the command onto the
/// QUndoStack does not apply them again. QUndoStack and History stay in lock-step: both are
/// linear stacks, both drop their redo lists when a new edit arrives.

#include <lucent/material/Brush.h>

#include <QUndoCommand>

#include <algorithm>
#include <functional>

namespace lucent::app {

/// What the pen pressure of a graphics tablet scales (the mouse always gives pressure 1).
enum class PressureMode { Off = 0, Radius = 1, Strength = 2, RadiusAndStrength = 3 };

/// Brush as the Tools dock edits it.
struct AppBrush {
    BrushSettings engine;  ///< radius (mm), falloff, strength, mode, channels, value, spacing
    /// Stamp centre placed this far below the picked surface point, along −normal (mm): 0 paints
    /// a hemisphere into the surface, radius paints a full sphere just under it.
    float depthMm = 0.f;
    PressureMode pressureMode = PressureMode::Strength;
    /// Smallest pressure factor, so a feather-light touch still paints a valid (radius > 0)
    /// stamp.
    static constexpr float MIN_PRESSURE = 0.05f;

    /// Factor on the radius of a stamp at tablet pressure `pressure` ∈ [0, 1].
    [[nodiscard]] float radiusScale(float pressure) const {
        const bool on =
            pressureMode == PressureMode::Radius || pressureMode == PressureMode::RadiusAndStrength;
        return on ? std::clamp(pressure, MIN_PRESSURE, 1.f) : 1.f;
    }
    /// Factor on the strength of a stamp at tablet pressure `pressure` ∈ [0, 1].
    [[nodiscard]] float strengthScale(float pressure) const {
        const bool on = pressureMode == PressureMode::Strength ||
                        pressureMode == PressureMode::RadiusAndStrength;
        return on ? std::clamp(pressure, MIN_PRESSURE, 1.f) : 1.f;
    }
};

/// One engine History step (stroke, fill, procedural fill, preset) on the QUndoStack.
class HistoryCommand : public QUndoCommand {
public:
    /// @param undoFn / redoFn call History::undo / History::redo on the document's volume.
    /// @param isPaint true for a step the engine's History holds (stroke, fill); false for
    ///        steps kept by value in the functions (lights, η).
    HistoryCommand(const QString& text, std::function<void()> undoFn, std::function<void()> redoFn,
                   bool isPaint = false)
        : QUndoCommand(text),
          m_undo(std::move(undoFn)),
          m_redo(std::move(redoFn)),
          m_isPaint(isPaint) {}
    [[nodiscard]] bool isPaint() const { return m_isPaint; }
    void undo() override { m_undo(); }
    void redo() override {
        if (m_applied) {  // QUndoStack::push calls redo(); the edit is already in the volume
            m_applied = false;
            return;
        }
        m_redo();
    }

private:
    std::function<void()> m_undo, m_redo;
    bool m_isPaint;
    bool m_applied = true;
};

}  // namespace lucent::app
