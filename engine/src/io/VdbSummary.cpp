// SPDX-License-Identifier: MIT
/// @file
/// @brief Text form of a VDB file summary (no OpenVDB here: the summary is plain data).

#include <lucent/io/VdbIO.h>

#include <iomanip>
#include <sstream>

namespace lucent::io {

namespace {
void printVector(std::ostream& os, const std::vector<double>& v) {
    os << '(';
    for (size_t k = 0; k < v.size(); ++k)
        os << (k ? ", " : "") << v[k];
    os << ')';
}
}  // namespace

std::string formatVdbSummary(const VdbFileSummary& s) {
    std::ostringstream os;
    os << std::setprecision(7);
    os << "file:     " << s.path << " (" << s.fileBytes << " bytes, VDB " << s.formatVersion
       << ")\n";
    if (!s.metadata.empty()) {
        os << "metadata:\n";
        for (const auto& [name, value] : s.metadata)
            os << "  " << name << " = " << value << '\n';
    }
    os << "grids:    " << s.grids.size() << '\n';
    for (const VdbGridSummary& g : s.grids) {
        os << "grid '" << g.name << "'\n";
        os << "  type:          " << g.valueType << " (" << g.gridClass << ")\n";
        if (!g.note.empty()) {
            os << "  " << g.note << '\n';
            continue;
        }
        os << "  active voxels: " << g.activeVoxelCount << " in " << g.leafCount << " leaves\n";
        if (g.activeBox.isEmpty()) {
            os << "  index bbox:    empty\n";
        } else {
            // In 64 bits: an int32 box can span more than 2^31 voxels per axis.
            const auto extent = [](int32_t lo, int32_t hi) { return int64_t(hi) - lo + 1; };
            os << "  index bbox:    [" << g.activeBox.lo.x << ' ' << g.activeBox.lo.y << ' '
               << g.activeBox.lo.z << "] .. [" << g.activeBox.hi.x << ' ' << g.activeBox.hi.y << ' '
               << g.activeBox.hi.z << "] (" << extent(g.activeBox.lo.x, g.activeBox.hi.x) << 'x'
               << extent(g.activeBox.lo.y, g.activeBox.hi.y) << 'x'
               << extent(g.activeBox.lo.z, g.activeBox.hi.z) << ")\n";
            os << "  world bbox:    (" << g.worldMin.x << ", " << g.worldMin.y << ", "
               << g.worldMin.z << ") .. (" << g.worldMax.x << ", " << g.worldMax.y << ", "
               << g.worldMax.z << ")\n";
        }
        os << "  voxel size:    (" << g.voxelSize.x << ", " << g.voxelSize.y << ", "
           << g.voxelSize.z << ")\n";
        if (g.components > 0) {
            os << "  value range:   ";
            if (g.minValue.empty()) {
                os << "no finite active values";
            } else {
                printVector(os, g.minValue);
                os << " .. ";
                printVector(os, g.maxValue);
            }
            os << '\n';
        } else {
            os << "  value range:   not summarised for this type\n";
        }
        if (g.nonFiniteCount)
            os << "  NON-FINITE:    " << g.nonFiniteCount << " active values are NaN/Inf\n";
        for (const auto& [name, value] : g.metadata)
            os << "  meta " << name << " = " << value << '\n';
    }
    return os.str();
}

}  // namespace lucent::io
