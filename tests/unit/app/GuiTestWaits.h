// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief How long the app's GUI tests wait for Xvfb to expose or activate a window.

namespace lucent::app::test {

/// Qt's default for qWaitForWindowExposed and qWaitForWindowActive is 5 s. Xvfb maps a window in
/// well under a second on an idle machine, but on the shared 2-core machine under the sanitizers
/// (load 14) the first exposure of the main window took longer than 5 s. The wait ends as soon
/// as the window is there, so a generous limit costs nothing when all is well; it is scaled like
/// every CTest time limit (LUCENT_TEST_TIMEOUT_SCALE: 6 under the sanitizers,
/// tests/CMakeLists.txt).
constexpr int kWindowWaitMs = 20000 * LUCENT_TEST_TIMEOUT_SCALE;

}  // namespace lucent::app::test
