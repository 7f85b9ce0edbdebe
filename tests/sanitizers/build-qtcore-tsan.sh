#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Builds Debian's own QtCore with ThreadSanitizer, for the app's TSan run (docs/benchmarks.md,
# "ThreadSanitizer": "The app's worker threads"). Benchmark-only; not part of CI.
#
# Why QtCore: the app's workers hand their results to the UI thread through queued signals, and
# QtCore's mutexes, wait conditions and event queue order those handoffs with atomics and
# futexes. Debian's libQt6Core is not instrumented, so TSan sees none of it and reports every
# handoff. The same source, patches and configure flags as Debian's package (debian/rules), with
# -fsanitize=thread added, give a drop-in library: the same ABI and features (the script checks
# qtcore-config.h against the installed one), loaded ahead of the system's through
# LD_LIBRARY_PATH by the `tsan` preset's app entries (cmake -DLUCENT_TSAN_QTCORE_DIR=...).
# QtGui, QtWidgets and the rest stay Debian's: they call QtCore's (now visible) primitives.
#
# Usage: tests/sanitizers/build-qtcore-tsan.sh [WORKDIR]   (default build/qtcore-tsan)
# Needs: the Debian source package from deb.debian.org (downloaded here), libglib2.0-dev and
# libb2-dev (for Debian's glib event dispatcher and BLAKE2 features), about 40 min on 2 cores.
# Prints the directory to pass as LUCENT_TSAN_QTCORE_DIR.
set -euo pipefail

workdir=$(realpath -m "${1:-build/qtcore-tsan}")
version=$(dpkg-query --show --showformat='${Version}' libqt6core6)   # e.g. 6.4.2+dfsg-10
upstream=${version%-*}                                                 # 6.4.2+dfsg
pool=http://deb.debian.org/debian/pool/main/q/qt6-base
mkdir -p "$workdir"
cd "$workdir"

for pkg in libglib2.0-dev libb2-dev; do
    if ! dpkg -s "$pkg" >/dev/null 2>&1; then
        echo "installing $pkg (Debian's QtCore is built with it)"
        DEBIAN_FRONTEND=noninteractive apt-get install -y -q "$pkg" >/dev/null
    fi
done

src=qtbase-everywhere-src-${upstream%+*}
if [[ ! -d $src ]]; then
    curl -fsSO "$pool/qt6-base_${upstream}.orig.tar.xz"
    curl -fsSO "$pool/qt6-base_${version}.debian.tar.xz"
    tar xf "qt6-base_${upstream}.orig.tar.xz"
    tar xf "qt6-base_${version}.debian.tar.xz" -C "$src"
    while read -r patch; do
        case "$patch" in "" | \#*) continue ;; esac
        patch -d "$src" -p1 -s <"$src/debian/patches/$patch"
    done <"$src/debian/patches/series"
fi

# debian/rules' configure flags that reach QtCore, the install layout (QLibraryInfo's compiled-in
# paths, so that Debian's plugins are found) and the sanitizer flags of the `tsan` preset.
multiarch=$(dpkg-architecture -qDEB_HOST_MULTIARCH)
tsan_flags="-fsanitize=thread -fno-omit-frame-pointer"
cmake -S "$src" -B build -G Ninja --log-level=WARNING \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_FLAGS="$tsan_flags" -DCMAKE_CXX_FLAGS="$tsan_flags" \
    -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=thread -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=thread \
    -DCMAKE_INSTALL_PREFIX=/usr -DINSTALL_BINDIR=lib/qt6/bin -DINSTALL_LIBDIR="lib/$multiarch" \
    -DINSTALL_LIBEXECDIR=lib/qt6/libexec -DINSTALL_ARCHDATADIR="lib/$multiarch/qt6" \
    -DINSTALL_DATADIR=share/qt6 -DINSTALL_HOSTDATADIR="lib/$multiarch/qt6" \
    -DINSTALL_SYSCONFDIR=/etc/xdg -DINSTALL_INCLUDEDIR="include/$multiarch/qt6" \
    -DINSTALL_PLUGINDIR="lib/$multiarch/qt6/plugins" -DINSTALL_TRANSLATIONDIR=share/qt6/translations \
    -DINSTALL_MKSPECSDIR="lib/$multiarch/qt6/mkspecs" \
    -DQT_BUILD_EXAMPLES=OFF -DQT_BUILD_TESTS=OFF -DFEATURE_sql=OFF \
    -DFEATURE_mimetype_database=OFF -DFEATURE_accessibility=ON -DFEATURE_doubleconversion=ON \
    -DFEATURE_glib=ON -DFEATURE_icu=ON -DFEATURE_pcre2=ON -DFEATURE_system_pcre2=ON \
    -DFEATURE_zlib=ON -DFEATURE_system_libb2=ON -DFEATURE_rpath=OFF -DFEATURE_relocatable=OFF

# A library with other features than the installed one would not be a drop-in replacement.
installed=/usr/include/$multiarch/qt6/QtCore/qtcore-config.h
if ! diff <(grep 'define QT_FEATURE' build/src/corelib/qtcore-config.h | sort) \
    <(grep 'define QT_FEATURE' "$installed" | sort); then
    echo "error: QtCore's features differ from the installed $installed (lines above)" >&2
    exit 1
fi

ninja -C build Core
echo "$workdir/build/lib/$multiarch"
