// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The planner's fitted models, embedded at build time (generated ModelData.cpp).

namespace lucent::planner::detail {

extern const char* const PLANNER_MODELS_JSON;  ///< resources/planner/models.json

}  // namespace lucent::planner::detail
