// SPDX-License-Identifier: MIT
// The work group's place on the line of groups that gpu::dispatchLine (GlResources.h) folds into
// x and z when the line is longer than one dispatch dimension allows (65535 groups).
#pragma once

uint lineGroup() {
    return gl_WorkGroupID.z * gl_NumWorkGroups.x + gl_WorkGroupID.x;
}
