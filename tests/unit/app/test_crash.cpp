// SPDX-License-Identifier: MIT
/// @file
/// @brief Nothing lost (issue 16 §5): the real `lucent` app, painting with its live preview,
/// autosaving and saving (its test-only --crash-test-script), is killed with SIGKILL in the
/// middle of a stroke and in the middle of a save. The last saved project and the autosave
/// must both load with exactly the material they were written with, and the app must reopen
/// them. Engine-level kills of saveProject are tested in tests/unit/scene/test_scene.cpp
/// (ProjectSave.SigkillAtAnyMomentLeavesOneWholeGeneration); this is the app around it.

#include <lucent/scene/SceneFile.h>

#include <QCoreApplication>
#include <QDir>
#include <QProcess>
#include <QProcessEnvironment>

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <string>
#include <vector>

namespace {

using namespace lucent;

/// Generous: the app starts under Xvfb on llvmpipe (2–5 s) and a 128³ project save takes
/// a fraction of a second; the sanitizer presets scale it.
constexpr int WAIT_MS = 60000 * LUCENT_TEST_TIMEOUT_SCALE;

QString testDir() {
    const QString dir = QStringLiteral(LUCENT_TEST_OUTPUT_DIR "/crash");
    QDir(dir).removeRecursively();
    QDir().mkpath(dir);
    return dir;
}

/// Content hash of the material of the project at `path`, as the app prints it.
QString materialHashOf(const QString& path) {
    const Scene s = loadScene(path.toStdString());
    if (s.objects.empty() || !s.objects[0].material)
        return QStringLiteral("no material");
    return QString::number(qulonglong(s.objects[0].material->contentHash()), 16);
}

/// The app running --crash-test-script on a project, its stdout read line by line.
class ScriptedApp {
public:
    ScriptedApp(const QString& project, const QString& home) {
        QProcessEnvironment env = QProcessEnvironment::systemEnvironment();
        env.insert(QStringLiteral("XDG_DATA_HOME"), home);  // the autosave goes here
        env.insert(QStringLiteral("XDG_CONFIG_HOME"), home);
        m_process.setProcessEnvironment(env);
        m_process.setProcessChannelMode(QProcess::ForwardedErrorChannel);
        m_process.start(QStringLiteral(LUCENT_APP_PATH),
                        {QStringLiteral("--crash-test-script"), QStringLiteral("--viewport"),
                         QStringLiteral("320x180"), project});
    }
    ~ScriptedApp() { killNow(); }

    /// Reads lines until one satisfies `match` (returned, split at spaces); empty on timeout or
    /// when the app exits first.
    QStringList waitFor(const std::function<bool(const QStringList&)>& match) {
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(WAIT_MS);
        while (std::chrono::steady_clock::now() < deadline) {
            while (m_process.canReadLine()) {
                const QStringList words = readLine();
                if (match(words))
                    return words;
            }
            if (m_process.state() == QProcess::NotRunning)
                return {};
            m_process.waitForReadyRead(200);
        }
        return {};
    }
    QStringList waitFor(const QString& first, const QString& second = {}) {
        return waitFor([&](const QStringList& w) {
            return !w.isEmpty() && w[0] == first && (second.isEmpty() || w.value(1) == second);
        });
    }
    /// SIGKILL (QProcess::kill), then the lines the app had written before it died.
    QStringList killNow() {
        if (m_process.state() == QProcess::NotRunning)
            return {};
        m_process.kill();
        m_process.waitForFinished(WAIT_MS);
        QStringList rest;
        while (m_process.canReadLine())
            rest.push_back(readLine().join(QLatin1Char(' ')));
        return rest;
    }
    [[nodiscard]] bool killedBySignal() const {
        return m_process.exitStatus() == QProcess::CrashExit;
    }
    /// Every line read so far (for failure messages).
    [[nodiscard]] std::string log() const { return m_log.join(QLatin1Char('\n')).toStdString(); }
    /// Last hashes of a finished autosave and a finished save ("" if none yet).
    QString lastAutosave, lastSave;

private:
    QStringList readLine() {
        const QString line = QString::fromUtf8(m_process.readLine()).trimmed();
        m_log.push_back(line);
        const QStringList w = line.split(QLatin1Char(' '));
        if (w.value(0) == QLatin1String("autosave") && w.value(1) == QLatin1String("end"))
            lastAutosave = w.value(3);
        if (w.value(0) == QLatin1String("save") && w.value(1) == QLatin1String("begin"))
            m_saving = w.value(3);
        if (w.value(0) == QLatin1String("save") && w.value(1) == QLatin1String("end"))
            lastSave = m_saving;
        return w;
    }

    QProcess m_process;
    QStringList m_log;
    QString m_saving;
};

TEST(AppCrash, SigkillMidStrokeAndMidSaveLosesNothingSaved) {
    const QString dir = testDir();
    const QString project = dir + QStringLiteral("/project.json");
    saveProject(makeDefaultScene(), project.toStdString());
    const QString initial = materialHashOf(project);
    QString autosave;

    // 1. Killed in the middle of a stroke, after at least one autosave and one save.
    {
        ScriptedApp app(project, dir);
        const QStringList path = app.waitFor(QStringLiteral("autosave-path"));
        ASSERT_EQ(path.size(), 2) << "the app did not start:\n" << app.log();
        autosave = path[1];
        ASSERT_TRUE(autosave.startsWith(dir)) << autosave.toStdString();
        const QStringList opened = app.waitFor(QStringLiteral("opened"));
        ASSERT_EQ(opened.value(1), initial) << app.log();
        ASSERT_FALSE(app.waitFor([&app](const QStringList&) {
                            return !app.lastSave.isEmpty() && !app.lastAutosave.isEmpty();
                        })
                         .isEmpty())
            << "no save and autosave:\n"
            << app.log();
        const QStringList open = app.waitFor(
            [](const QStringList& w) { return w.value(0) == "stroke" && w.value(2) == "open"; });
        ASSERT_FALSE(open.isEmpty()) << app.log();
        const QStringList rest = app.killNow();
        EXPECT_TRUE(app.killedBySignal());
        EXPECT_FALSE(rest.contains(QStringLiteral("stroke %1 closed").arg(open[1])))
            << "the kill came after the stroke ended, not during it";
        EXPECT_NE(app.lastSave, initial) << "the saves must have written the painting";
        EXPECT_EQ(materialHashOf(project), app.lastSave) << "the last saved project changed";
        EXPECT_EQ(materialHashOf(autosave), app.lastAutosave) << "the autosave changed";
    }

    // 2. Reopened by the app (the saved material, as saved), then killed in the middle of a save.
    {
        const QString saved = materialHashOf(project);
        const QString autosaved = materialHashOf(autosave);
        ScriptedApp app(project, dir);
        EXPECT_EQ(app.waitFor(QStringLiteral("opened")).value(1), saved) << app.log();
        const QStringList begin = app.waitFor(QStringLiteral("save"), QStringLiteral("begin"));
        ASSERT_EQ(begin.size(), 4) << app.log();
        const QStringList rest = app.killNow();
        EXPECT_TRUE(app.killedBySignal());
        EXPECT_FALSE(rest.contains(QStringLiteral("save end %1").arg(begin[2])))
            << "the kill came after the save ended, not during it";
        // An atomic save: the previous project whole, or (killed after the rename) the new one.
        const QString lastSaved = materialHashOf(project);
        EXPECT_TRUE(lastSaved == saved || lastSaved == begin[3])
            << "the project holds neither the saved nor the saving material";
        EXPECT_NE(begin[3], saved) << "the interrupted save had new paint to write";
        const QString expectedAutosave = app.lastAutosave.isEmpty() ? autosaved : app.lastAutosave;
        EXPECT_EQ(materialHashOf(autosave), expectedAutosave);
    }

    // 3. The app reopens both files after the second kill (recovery opens the autosave the
    //    same way).
    for (const QString& file : {project, autosave}) {
        const QString expected = materialHashOf(file);  // before the app autosaves over it
        ScriptedApp app(file, dir);
        EXPECT_EQ(app.waitFor(QStringLiteral("opened")).value(1), expected)
            << file.toStdString() << "\n"
            << app.log();
        app.killNow();
    }
}

}  // namespace

int main(int argc, char** argv) {
    QCoreApplication app(argc, argv);
    ::testing::InitGoogleTest(&argc, argv);
    return RUN_ALL_TESTS();
}
