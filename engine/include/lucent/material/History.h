// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Undo/redo of painting as per-stroke brick deltas, and PaintSession, the command
/// interface the app drives.
///
///     History history;
///     PaintSession session(vol, history);
///     session.beginStroke(brush);
///     session.strokeTo(p0); session.strokeTo(p1);   // stamps every spacing·radius mm
///     session.endStroke();
///     session.undo();                               // vol is bit-identical to before the stroke
///
/// A stroke stores one copy of only the bricks it touched (8³ voxels × 9 floats = 18 KiB each):
/// the "before" state while applied; undo swaps it with the volume's bricks, so the copy then
/// holds the "after" state for redo. Memory is proportional to the touched bricks. When bytesUsed()
/// exceeds the budget the oldest strokes are dropped.

#include <lucent/core/Types.h>
#include <lucent/material/Brush.h>
#include <lucent/material/MaterialVolume.h>
#include <lucent/material/Procedural.h>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace lucent {

class History {
public:
    static constexpr size_t DEFAULT_BUDGET_BYTES = size_t(512) << 20;

    /// @param budgetBytes memory cap of the stored strokes (≥ 1 brick pair).
    explicit History(size_t budgetBytes = DEFAULT_BUDGET_BYTES);

    /// Opens a stroke on `volume`. @throw ValueError if a stroke is already open, or the
    /// volume's grid differs from the one this history was recorded on (call clear() first).
    void beginStroke(const MaterialVolume& volume, std::string label = {});
    /// Saves the current content of brick b as its "before" state, once per stroke. A no-op
    /// when no stroke is open. Called by the painting operations before they modify b.
    void recordBrick(const MaterialVolume& volume, int b);
    /// Closes the stroke: saves the "after" state of its bricks and clears the redo list.
    /// A stroke that touched nothing is dropped. @return true if a stroke was stored.
    bool endStroke(const MaterialVolume& volume);
    /// Closes the stroke and restores its bricks' "before" state; nothing is stored.
    void cancelStroke(MaterialVolume& volume);
    [[nodiscard]] bool isStrokeOpen() const { return m_open.has_value(); }

    [[nodiscard]] bool canUndo() const { return !m_undo.empty(); }
    [[nodiscard]] bool canRedo() const { return !m_redo.empty(); }
    /// Restores the bricks of the last stroke (bit-exact), marks them dirty.
    /// @return false if there is nothing to undo. @throw ValueError if a stroke is open or the
    /// volume's grid differs.
    bool undo(MaterialVolume& volume);
    /// Re-applies the last undone stroke. @return false if there is nothing to redo.
    bool redo(MaterialVolume& volume);

    [[nodiscard]] size_t undoCount() const { return m_undo.size(); }
    [[nodiscard]] size_t redoCount() const { return m_redo.size(); }
    /// Label of the stroke undo() would revert (empty if none).
    [[nodiscard]] std::string undoLabel() const;
    /// Bytes held by stored strokes (brick copies and indices).
    [[nodiscard]] size_t bytesUsed() const { return m_bytes; }
    [[nodiscard]] size_t budgetBytes() const { return m_budget; }
    /// Changes the memory cap (≥ 1 brick pair, as in the constructor); the oldest strokes go at
    /// once when the stored ones exceed it (the newest is always kept). @throw ValueError.
    void setBudgetBytes(size_t budgetBytes);
    /// Forgets every stroke (and an open one, without restoring it).
    void clear();

private:
    struct Stroke {
        std::string label;
        std::vector<int> bricks;
        /// bricks.size() × brick floats: the "before" state while the stroke is applied, the
        /// "after" state while it is undone (undo/redo swap it with the volume's bricks).
        std::vector<float> data;
        [[nodiscard]] size_t bytes() const;
    };
    void checkVolume(const MaterialVolume& volume) const;
    void swapBricks(MaterialVolume& volume, Stroke& s) const;
    void enforceBudget();

    size_t m_budget;
    size_t m_bytes = 0;
    std::optional<GridSpec> m_spec;
    std::optional<Stroke> m_open;
    std::vector<int32_t> m_slotOfBrick;  // during an open stroke: index into m_open->bricks
    std::deque<Stroke> m_undo;
    std::vector<Stroke> m_redo;
};

/// Painting commands on one volume with undo: what the app's tools call.
class PaintSession {
public:
    /// Both must outlive the session.
    PaintSession(MaterialVolume& volume, History& history);

    /// Starts an interactive stroke with `brush` (validated). @throw ValueError.
    void beginStroke(const BrushSettings& brush, std::string label = "stroke");
    /// Extends the stroke to p (mm): stamps at every spacing·radius along the path so far,
    /// the first at the first point. @throw ValueError if no stroke is open or p is not finite.
    void strokeTo(const Point3f& p);
    /// Ends the interactive stroke (one undo step).
    void endStroke();
    [[nodiscard]] bool isStrokeOpen() const { return m_stroking; }

    /// One-shot commands, each one undo step.
    void stamp(const BrushSettings& brush, const Point3f& center);
    void stroke(const BrushSettings& brush, const std::vector<Point3f>& path);
    void fill(const MaterialSample& value, ChannelMask channels = ALL_CHANNELS);
    void fillProcedural(const ProceduralFill& fill);
    /// Sets the base material and repaints the interior with it (one undo step); η is not undone.
    void applyPreset(const MaterialSample& base, float eta);

    bool undo() { return m_history.undo(m_volume); }
    bool redo() { return m_history.redo(m_volume); }
    [[nodiscard]] MaterialVolume& volume() { return m_volume; }
    [[nodiscard]] History& history() { return m_history; }

private:
    MaterialVolume& m_volume;
    History& m_history;
    bool m_stroking = false;
    BrushSettings m_brush;
    std::optional<Point3f> m_last;  // last path point of the interactive stroke
    float m_carry = 0.f;            // arc length travelled since the last stamp, mm
};

}  // namespace lucent
