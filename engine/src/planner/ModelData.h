// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief The planner's fitted models and live costs, embedded at build time (generated
/// ModelData.cpp).

namespace lucent::planner::detail {

extern const char* const PLANNER_MODELS_JSON;      ///< resources/planner/models.json
extern const char* const PLANNER_LIVE_COSTS_JSON;  ///< resources/planner/live_costs.json

}  // namespace lucent::planner::detail
