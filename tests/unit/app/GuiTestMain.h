// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief main() of a GUI test executable: the app's GL surface format, a QApplication, the
/// tests, and the shared objects kept loaded to exit (KeepLibrariesLoaded.h).

#include "KeepLibrariesLoaded.h"
#include "MainWindow.h"

#include <QApplication>

#include <gtest/gtest.h>

namespace lucent::app::test {

inline int runGuiTests(int argc, char** argv) {
    MainWindow::useGlSurfaceFormat();
    QApplication app(argc, argv);
    ::testing::InitGoogleTest(&argc, argv);
    const int result = RUN_ALL_TESTS();
    keepLibrariesLoaded();  // LSan names the GL driver's leaks at exit
    return result;
}

}  // namespace lucent::app::test
