// SPDX-License-Identifier: MIT
/// @file
/// @brief Per-stroke brick-delta undo/redo and PaintSession (History.h).
#include <lucent/material/History.h>

#include <lucent/core/Error.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace lucent {

namespace {
constexpr size_t BRICK_FLOATS = size_t(MaterialVolume::BRICK_VOXELS) * MaterialVolume::COMPONENTS;
}

size_t History::Stroke::bytes() const {
    return sizeof(Stroke) + label.capacity() + bricks.capacity() * sizeof(int) +
           data.capacity() * sizeof(float);
}

History::History(size_t budgetBytes) : m_budget(budgetBytes) {
    setBudgetBytes(budgetBytes);
}

void History::setBudgetBytes(size_t budgetBytes) {
    LUCENT_CHECK(budgetBytes >= BRICK_FLOATS * sizeof(float), "History: budget of ", budgetBytes,
                 " bytes cannot hold one brick (", BRICK_FLOATS * sizeof(float), " bytes)");
    m_budget = budgetBytes;
    enforceBudget();
}

void History::checkVolume(const MaterialVolume& volume) const {
    LUCENT_CHECK(volume.brickCount() > 0, "History: the material volume is empty");
    LUCENT_CHECK(!m_spec || *m_spec == volume.spec(),
                 "History: the volume's grid differs from the one this history was recorded on "
                 "(clear() the history after replacing the volume)");
}

void History::beginStroke(const MaterialVolume& volume, std::string label) {
    LUCENT_CHECK(!m_open, "History::beginStroke: a stroke is already open");
    checkVolume(volume);
    m_spec = volume.spec();
    m_open = Stroke{};
    m_open->label = std::move(label);
    m_slotOfBrick.assign(size_t(volume.brickCount()), -1);
}

void History::recordBrick(const MaterialVolume& volume, int b) {
    if (!m_open)
        return;
    LUCENT_CHECK(b >= 0 && size_t(b) < m_slotOfBrick.size(), "History::recordBrick: brick ", b,
                 " is not in the grid the open stroke was started on");
    if (m_slotOfBrick[size_t(b)] >= 0)
        return;
    m_slotOfBrick[size_t(b)] = int32_t(m_open->bricks.size());
    m_open->bricks.push_back(b);
    const float* src = volume.brickData(b);
    m_open->data.insert(m_open->data.end(), src, src + BRICK_FLOATS);
}

bool History::endStroke(const MaterialVolume& volume) {
    LUCENT_CHECK(m_open, "History::endStroke: no stroke is open");
    checkVolume(volume);
    Stroke s = std::move(*m_open);
    m_open.reset();
    m_slotOfBrick.clear();
    if (s.bricks.empty())
        return false;
    s.data.shrink_to_fit();
    s.bricks.shrink_to_fit();
    for (const Stroke& r : m_redo)
        m_bytes -= r.bytes();
    m_redo.clear();
    m_bytes += s.bytes();
    m_undo.push_back(std::move(s));
    enforceBudget();
    return true;
}

void History::cancelStroke(MaterialVolume& volume) {
    LUCENT_CHECK(m_open, "History::cancelStroke: no stroke is open");
    checkVolume(volume);
    Stroke s = std::move(*m_open);
    m_open.reset();
    m_slotOfBrick.clear();
    swapBricks(volume, s);
}

void History::swapBricks(MaterialVolume& volume, Stroke& s) const {
    for (size_t i = 0; i < s.bricks.size(); ++i) {
        float* brick = volume.brickData(s.bricks[i]);
        std::swap_ranges(brick, brick + BRICK_FLOATS,
                         s.data.begin() + std::ptrdiff_t(i * BRICK_FLOATS));
        volume.markBrickDirty(s.bricks[i]);
    }
}

bool History::undo(MaterialVolume& volume) {
    LUCENT_CHECK(!m_open, "History::undo: a stroke is open (end or cancel it first)");
    if (m_undo.empty())
        return false;
    checkVolume(volume);
    swapBricks(volume, m_undo.back());  // volume ← before, stored ← after
    m_redo.push_back(std::move(m_undo.back()));
    m_undo.pop_back();
    return true;
}

bool History::redo(MaterialVolume& volume) {
    LUCENT_CHECK(!m_open, "History::redo: a stroke is open (end or cancel it first)");
    if (m_redo.empty())
        return false;
    checkVolume(volume);
    swapBricks(volume, m_redo.back());  // volume ← after, stored ← before
    m_undo.push_back(std::move(m_redo.back()));
    m_redo.pop_back();
    return true;
}

std::string History::undoLabel() const {
    return m_undo.empty() ? std::string() : m_undo.back().label;
}

void History::enforceBudget() {
    // Oldest strokes go first; the newest stroke is always kept so the last edit can be undone.
    while (m_bytes > m_budget && m_undo.size() > 1) {
        m_bytes -= m_undo.front().bytes();
        m_undo.pop_front();
    }
}

void History::clear() {
    m_open.reset();
    m_slotOfBrick.clear();
    m_undo.clear();
    m_redo.clear();
    m_bytes = 0;
    m_spec.reset();
}

// PaintSession -------------------------------------------------------------------------------

PaintSession::PaintSession(MaterialVolume& volume, History& history)
    : m_volume(volume), m_history(history) {}

void PaintSession::beginStroke(const BrushSettings& brush, std::string label) {
    LUCENT_CHECK(!m_stroking, "PaintSession::beginStroke: a stroke is already open");
    validateBrush(brush);
    m_history.beginStroke(m_volume, std::move(label));
    m_brush = brush;
    m_stroking = true;
    m_last.reset();
    m_carry = 0.f;
}

void PaintSession::strokeTo(const Point3f& p) {
    LUCENT_CHECK(m_stroking, "PaintSession::strokeTo: no stroke is open");
    LUCENT_CHECK(isFinite(p), "PaintSession::strokeTo: point is not finite");
    const float s = m_brush.spacing * m_brush.radius;
    if (!m_last) {
        lucent::stamp(m_volume, m_brush, p, &m_history);
        m_last = p;
        m_carry = 0.f;
        return;
    }
    const Vector3f d = p - *m_last;
    const float len = glm::length(d);
    LUCENT_CHECK(len / s <= float(BrushSettings::MAX_STAMPS_PER_STROKE),
                 "PaintSession::strokeTo: segment of ", len, " mm needs too many stamps");
    // Stamps continue the spacing of the previous segments: the next one is s − carry away.
    float at = s - m_carry;
    while (at <= len) {
        lucent::stamp(m_volume, m_brush, *m_last + d * (at / len), &m_history);
        at += s;
    }
    m_carry = len - (at - s);
    m_last = p;
}

void PaintSession::endStroke() {
    LUCENT_CHECK(m_stroking, "PaintSession::endStroke: no stroke is open");
    m_stroking = false;
    m_history.endStroke(m_volume);
}

void PaintSession::stamp(const BrushSettings& brush, const Point3f& center) {
    LUCENT_CHECK(!m_stroking, "PaintSession::stamp: an interactive stroke is open");
    validateBrush(brush);
    m_history.beginStroke(m_volume, "stamp");
    try {
        lucent::stamp(m_volume, brush, center, &m_history);
    } catch (...) {
        m_history.cancelStroke(m_volume);
        throw;
    }
    m_history.endStroke(m_volume);
}

void PaintSession::stroke(const BrushSettings& brush, const std::vector<Point3f>& path) {
    LUCENT_CHECK(!m_stroking, "PaintSession::stroke: an interactive stroke is open");
    const std::vector<Point3f> stamps = strokeStamps(path, brush);  // validates before any change
    m_history.beginStroke(m_volume, "stroke");
    for (const Point3f& p : stamps)
        lucent::stamp(m_volume, brush, p, &m_history);
    m_history.endStroke(m_volume);
}

void PaintSession::fill(const MaterialSample& value, ChannelMask channels) {
    LUCENT_CHECK(!m_stroking, "PaintSession::fill: an interactive stroke is open");
    m_history.beginStroke(m_volume, "fill");
    try {
        fillInterior(m_volume, value, channels, &m_history);
    } catch (...) {
        m_history.cancelStroke(m_volume);
        throw;
    }
    m_history.endStroke(m_volume);
}

void PaintSession::fillProcedural(const ProceduralFill& fill) {
    LUCENT_CHECK(!m_stroking, "PaintSession::fillProcedural: an interactive stroke is open");
    m_history.beginStroke(m_volume, "procedural fill");
    try {
        lucent::fillProcedural(m_volume, fill, &m_history);
    } catch (...) {
        m_history.cancelStroke(m_volume);
        throw;
    }
    m_history.endStroke(m_volume);
}

void PaintSession::applyPreset(const MaterialSample& base, float eta) {
    LUCENT_CHECK(!m_stroking, "PaintSession::applyPreset: an interactive stroke is open");
    m_volume.setEta(eta);  // validates first
    const MaterialSample clean = sanitize(base);
    fill(clean);
    m_volume.setBase(clean);
}

}  // namespace lucent
