/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
// Scripted tests of the workbench under a display (Xvfb in ctest): the window is driven
// through its public actions and, for the rubber band, through VTK's own mouse events.
#include "vuWorkbenchWindow.h"

#include "itkFlatteningDistortionCalculator.h"
#include "itkMassSpringSheetFlattener.h"
#include "vuSheetMeshIO.h"

#include <nlohmann/json.hpp>

#include <QApplication>
#include <QFile>
#include <QProcess>
#include <QSlider>
#include <QSurfaceFormat>
#include <QVTKOpenGLNativeWidget.h>
#include <QtTest>

#include <vtkCamera.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>

#include <fstream>
#include <set>

namespace {
double
EdgeStrainP95(const itk::SheetMesh & surface, const itk::SheetMesh & flat)
{
  auto calculator = itk::FlatteningDistortionCalculator::New();
  calculator->SetSurfaceMesh(surface);
  calculator->SetFlatMesh(flat);
  calculator->Compute();
  return calculator->GetEdgeStrainP95();
}

// Pixels of a screenshot that are clearly red (locked particles) and clearly blue (free).
void
CountColours(const QImage & image, size_t & red, size_t & blue)
{
  red = blue = 0;
  for (int y = 0; y < image.height(); ++y)
  {
    for (int x = 0; x < image.width(); ++x)
    {
      const QColor c = image.pixelColor(x, y);
      red += c.red() > 190 && c.green() < 90 && c.blue() < 90 ? 1 : 0;
      blue += c.blue() > 190 && c.red() < 110 && c.green() < 160 ? 1 : 0;
    }
  }
}

// Standard deviation of the grey levels in the middle of a screenshot (a texture shows
// structure; a plain surface does not).
double
GreyDeviation(const QImage & image)
{
  double sum = 0.0, sum2 = 0.0, n = 0.0;
  for (int y = image.height() / 4; y < 3 * image.height() / 4; ++y)
  {
    for (int x = image.width() / 4; x < 3 * image.width() / 4; ++x)
    {
      const double g = qGray(image.pixel(x, y));
      sum += g;
      sum2 += g * g;
      n += 1.0;
    }
  }
  return std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
}

int
RunTool(const QStringList & arguments, QString * errors = nullptr)
{
  QProcess tool;
  tool.start(VU_TOOL_PATH, arguments);
  tool.waitForFinished(600000);
  if (errors != nullptr)
  {
    *errors = QString::fromLocal8Bit(tool.readAllStandardError());
  }
  return tool.exitStatus() == QProcess::NormalExit ? tool.exitCode() : -1;
}
} // namespace

class WorkbenchGuiTest : public QObject
{
  Q_OBJECT

private:
  QString                              m_Work;
  QString                              m_Volume;
  std::unique_ptr<vu::WorkbenchWindow> m_Window;
  std::vector<uint32_t>                m_Outer;

  void
  WaitIdle(int milliseconds = 120000)
  {
    QTRY_VERIFY_WITH_TIMEOUT(!m_Window->IsBusy(), milliseconds);
  }

  // Starts the simulation with `integrator` on its automatic time step, not flattening when
  // the sheet hangs still; returns the controls set.
  vu::SimulationControls
  StartWith(itk::MassSpringIntegratorEnum integrator)
  {
    vu::SimulationControls controls = m_Window->GetControls();
    controls.Integrator = integrator;
    controls.TimeStep = 0.0;
    controls.AutoAdvance = false;
    m_Window->SetControls(controls);
    m_Window->StartSimulation();
    return controls;
  }

private slots:
  void
  initTestCase()
  {
    m_Work = qEnvironmentVariable("VU_WORKBENCH_TEST_DIR", QDir::tempPath() + "/vu-workbench-test");
    QDir(m_Work).removeRecursively();
    QVERIFY(QDir().mkpath(m_Work));
    QString errors;
    QCOMPARE(RunTool({ "phantom", "standard", "-o", m_Work + "/standard", "--format", "mha" }, &errors), 0);
    m_Volume = m_Work + "/standard/volume.mha";
    qputenv("VU_TOOL", VU_TOOL_PATH); // the exporting tool, beside the program when installed
    m_Window = std::make_unique<vu::WorkbenchWindow>();
    m_Window->resize(1400, 900);
    m_Window->show();
    QVERIFY(QTest::qWaitForWindowExposed(m_Window.get()));
  }

  void
  corruptInputShowsAnErrorAndTheProgramGoesOn()
  {
    const QString corrupt = m_Work + "/corrupt.mha";
    QFile         file(corrupt);
    QVERIFY(file.open(QIODevice::WriteOnly));
    file.write("ObjectType = Image\nNDims = 3\nDimSize = 50 50 50\nElementType = MET_SHORT\nElementDataFile = LOCAL\n"
               "garbage");
    file.close();
    m_Window->OpenScan(corrupt);
    WaitIdle();
    QVERIFY(!m_Window->GetLastError().isEmpty());
    QVERIFY(!m_Window->HasSheet());
    QVERIFY(m_Window->isVisible());
    qInfo() << "error shown:" << m_Window->GetLastError();
    m_Window->OpenScan(m_Work + "/no-such-scan.mha");
    WaitIdle();
    QVERIFY(!m_Window->GetLastError().isEmpty());
  }

  void
  opensTheStandardPhantom()
  {
    m_Window->OpenScan(m_Volume);
    WaitIdle();
    QVERIFY2(m_Window->GetLastError().isEmpty(), qPrintable(m_Window->GetLastError()));
    QVERIFY(m_Window->HasSheet());
    QVERIFY(m_Window->GetScene().Surface.IsGridStructured());
    // The texture on the sheet's grid layout follows the load.
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetTextureVersion() > 0 && !m_Window->IsBusy(), 60000);
    m_Outer =
      itk::MassSpringSheetFlattener::EdgeParticles(m_Window->GetScene().Surface, itk::SheetLockedEdgeEnum::OuterEdge);
    QVERIFY(!m_Outer.empty());
  }

  void
  rubberBandLocksTheOuterEdge()
  {
    // Seen along the roll axis, the outer edge is a short line at the end of the spiral:
    // a rectangle around it, drawn with the left button in lock mode.
    m_Window->SetParallelProjection(true);
    m_Window->SetStandardView(2, true);
    double lo[2] = { 1e9, 1e9 }, hi[2] = { -1e9, -1e9 };
    for (uint32_t id : m_Outer)
    {
      double d[2];
      QVERIFY(m_Window->ProjectParticle(id, d));
      for (int k = 0; k < 2; ++k)
      {
        lo[k] = std::min(lo[k], d[k]);
        hi[k] = std::max(hi[k], d[k]);
      }
    }
    m_Window->SetInteraction(vu::WorkbenchWindow::Interaction::Lock);
    vtkRenderWindowInteractor * interactor = m_Window->GetSheetView()->interactor();
    interactor->SetEventInformation(static_cast<int>(lo[0]) - 3, static_cast<int>(lo[1]) - 3);
    interactor->InvokeEvent(vtkCommand::LeftButtonPressEvent);
    interactor->SetEventInformation(static_cast<int>(hi[0]) + 3, static_cast<int>(hi[1]) + 3);
    interactor->InvokeEvent(vtkCommand::MouseMoveEvent);
    interactor->InvokeEvent(vtkCommand::LeftButtonReleaseEvent);
    m_Window->SetInteraction(vu::WorkbenchWindow::Interaction::Camera);
    const auto               locked = m_Window->GetLockedParticles();
    const std::set<uint32_t> lockedSet(locked.begin(), locked.end());
    for (uint32_t id : m_Outer)
    {
      QVERIFY2(lockedSet.count(id) == 1, "an outer-edge particle was not locked");
    }
    // Nothing far from the edge: every locked particle within two columns of it.
    const auto & surface = m_Window->GetScene().Surface;
    const int    edgeColumn = surface.GridIndex[2 * m_Outer.front() + 1];
    for (uint32_t id : locked)
    {
      QVERIFY2(std::abs(surface.GridIndex[2 * id + 1] - edgeColumn) <= 2,
               qPrintable(QString("particle %1 in column %2 locked, the edge is column %3; rectangle %4 x %5 pixels")
                            .arg(id)
                            .arg(surface.GridIndex[2 * id + 1])
                            .arg(edgeColumn)
                            .arg(hi[0] - lo[0] + 6)
                            .arg(hi[1] - lo[1] + 6)));
    }
    qInfo() << "rubber band locked" << locked.size() << "particles, outer edge" << m_Outer.size();
    // Screenshot: locked particles red, free ones blue.
    m_Window->SetParallelProjection(false);
    m_Window->SetStandardView(0, true);
    m_Window->SetShown(true, false, true);
    const QImage shot = m_Window->GrabSheetView();
    shot.save(m_Work + "/locked.png");
    size_t red = 0, blue = 0;
    CountColours(shot, red, blue);
    qInfo() << "screenshot: red pixels" << red << "blue pixels" << blue;
    QVERIFY(red > 20);
    QVERIFY(blue > 2 * red);
  }

  void
  unrollsWithRk4SwitchesToImplicitAndFlattens()
  {
    const auto             locks = m_Window->GetLockedParticles();
    vu::SimulationControls controls = StartWith(itk::MassSpringIntegratorEnum::RungeKutta4);
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetSnapshot().Step > 200, 60000);
    QCOMPARE(m_Window->GetSnapshot().Integrator, itk::MassSpringIntegratorEnum::RungeKutta4);
    // Lock and release while it runs.
    uint32_t free = 0;
    while (std::find(locks.begin(), locks.end(), free) != locks.end())
    {
      ++free;
    }
    m_Window->SetLocked({ free }, true);
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetSnapshot().Locked.size() > free && m_Window->GetSnapshot().Locked[free] == 1,
                             10000);
    m_Window->SetLocked({ free }, false);
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetSnapshot().Locked[free] == 0, 10000);
    QCOMPARE(m_Window->GetLockedParticles(), locks);
    // Switch to the implicit solver mid-run, then flatten.
    controls.Integrator = itk::MassSpringIntegratorEnum::ImplicitEuler;
    m_Window->SetControls(controls);
    QTRY_COMPARE_WITH_TIMEOUT(m_Window->GetSnapshot().Integrator, itk::MassSpringIntegratorEnum::ImplicitEuler, 10000);
    const uint64_t switched = m_Window->GetSnapshot().Step;
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetSnapshot().Step > switched + 100, 60000);
    // The whole window mid-run, for the eye (README).
    m_Window->SetShown(true, false, true);
    m_Window->SetStandardView(1, false);
    m_Window->GetSheetRenderer()->GetActiveCamera()->Azimuth(35.0);
    m_Window->GetSheetRenderer()->GetActiveCamera()->Elevation(20.0);
    m_Window->GetSheetRenderer()->ResetCameraClippingRange();
    QTest::qWait(200);
    m_Window->grab().save(m_Work + "/window.png");
    m_Window->FlattenNow();
    QTRY_COMPARE_WITH_TIMEOUT(m_Window->GetSnapshot().State, vu::SimulationSnapshot::Status::Finished, 120000);
    itk::SheetMesh flat;
    QVERIFY(m_Window->GetFlatResult(flat));
    const auto & surface = m_Window->GetScene().Surface;
    const double gui = EdgeStrainP95(surface, flat);
    // The command-line tool with the same locks.
    vu::WriteSheetMeshVtp((m_Work + "/surface.vtp").toStdString(), surface);
    QStringList arguments = { "flatten",  m_Work + "/surface.vtp",     "-o",           m_Work + "/cli-flat.obj",
                              "--report", m_Work + "/cli-report.json", "--coarsening", "1",
                              "--lock" };
    for (uint32_t id : locks)
    {
      arguments << QString::number(id);
    }
    QString errors;
    QVERIFY2(RunTool(arguments, &errors) == 0, qPrintable(errors));
    std::ifstream        report((m_Work + "/cli-report.json").toStdString());
    const nlohmann::json json = nlohmann::json::parse(report);
    const double         cli = json.at("distortion").at("edge_strain").at("p95").get<double>();
    qInfo() << "edge strain p95: workbench" << gui << "command-line tool" << cli;
    QVERIFY(std::abs(gui - cli) <= 0.1 * cli);
    m_Window->GrabFlatView().save(m_Work + "/flat.png");
  }

  void
  focalPlaneSliderChangesTheTexture()
  {
    QTRY_VERIFY_WITH_TIMEOUT(!m_Window->IsBusy(), 60000);
    const std::vector<unsigned char> before = m_Window->GetTexture().Pixels;
    const uint64_t                   version = m_Window->GetTextureVersion();
    QVERIFY(!before.empty());
    const QImage flatShot = m_Window->GrabFlatView();
    qInfo() << "flat view grey deviation" << GreyDeviation(flatShot);
    QVERIFY(GreyDeviation(flatShot) > 12.0); // the text on the sheet is visible
    // The offset slider itself, moved to 0.3 mm off the sheet (30 steps of 0.01 mm).
    auto * offset = m_Window->findChild<QSlider *>("focal-plane offset");
    QVERIFY(offset != nullptr);
    offset->setValue(30);
    QCOMPARE(m_Window->GetFocalPlane().Offset, 0.3);
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetTextureVersion() > version && !m_Window->IsBusy(), 60000);
    const std::vector<unsigned char> & after = m_Window->GetTexture().Pixels;
    QCOMPARE(after.size(), before.size());
    double difference = 0.0;
    for (size_t k = 0; k < after.size(); ++k)
    {
      difference += std::abs(int(after[k]) - int(before[k]));
    }
    difference /= static_cast<double>(after.size());
    qInfo() << "mean texture change with the focal plane 0.3 mm off the sheet:" << difference;
    QVERIFY(difference > 2.0);
    vu::FocalPlane plane = m_Window->GetFocalPlane();
    plane.Offset = 0.0;
    m_Window->SetFocalPlane(plane);
    QTRY_VERIFY_WITH_TIMEOUT(!m_Window->IsBusy(), 60000);
    m_Window->SetStandardView(0, true);
    m_Window->GrabSheetView().save(m_Work + "/textured.png");
  }

  void
  divergenceIsShownAndRecovered()
  {
    m_Window->ResetSimulation();
    vu::SimulationControls controls = StartWith(itk::MassSpringIntegratorEnum::SymplecticEuler);
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetSnapshot().Step > 300, 60000);
    const double stable = m_Window->GetSnapshot().TimeStep;
    controls.TimeStep = 40.0 * stable;
    m_Window->SetControls(controls);
    QTRY_COMPARE_WITH_TIMEOUT(m_Window->GetSnapshot().State, vu::SimulationSnapshot::Status::Diverged, 60000);
    QVERIFY(m_Window->GetLastError().contains("diverged"));
    qInfo() << m_Window->GetLastError();
    QVERIFY(m_Window->RecoverFromDivergence());
    QVERIFY(m_Window->GetLastError().isEmpty());
    QCOMPARE(m_Window->GetControls().TimeStep, 0.0); // the automatic step it ran on before
    QTRY_COMPARE_WITH_TIMEOUT(m_Window->GetSnapshot().State, vu::SimulationSnapshot::Status::Paused, 30000);
    const uint64_t resumed = m_Window->GetSnapshot().Step;
    m_Window->SetPaused(false);
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetSnapshot().Step > resumed + 500, 60000);
    QCOMPARE(m_Window->GetSnapshot().State, vu::SimulationSnapshot::Status::Running);
    // A wave, given while paused (applied at once, without a step): the kinetic energy
    // changes by what the impulse adds; then it runs on without diverging.
    m_Window->SetPaused(true);
    QTRY_COMPARE_WITH_TIMEOUT(m_Window->GetSnapshot().State, vu::SimulationSnapshot::Status::Paused, 10000);
    QTest::qWait(100);
    const double   still = m_Window->GetSnapshot().KineticEnergy;
    const uint64_t before = m_Window->GetSnapshot().Step;
    m_Window->Wave();
    QTRY_VERIFY_WITH_TIMEOUT(std::abs(m_Window->GetSnapshot().KineticEnergy - still) > 0.1 * still, 10000);
    QCOMPARE(m_Window->GetSnapshot().Step, before);
    qInfo() << "kinetic energy before the wave" << still << "after" << m_Window->GetSnapshot().KineticEnergy;
    m_Window->SetPaused(false);
    const uint64_t waved = m_Window->GetSnapshot().Step;
    QTRY_VERIFY_WITH_TIMEOUT(m_Window->GetSnapshot().Step > waved + 200, 60000);
    QVERIFY(m_Window->GetSnapshot().State != vu::SimulationSnapshot::Status::Diverged);
    m_Window->SetPaused(true);
    QTRY_COMPARE_WITH_TIMEOUT(m_Window->GetSnapshot().State, vu::SimulationSnapshot::Status::Paused, 10000);
    const uint64_t paused = m_Window->GetSnapshot().Step;
    m_Window->StepSimulation();
    QTRY_COMPARE_WITH_TIMEOUT(m_Window->GetSnapshot().Step, paused + 1, 10000);
    QTest::qWait(300);
    QCOMPARE(m_Window->GetSnapshot().Step, paused + 1);
  }

  void
  sessionFileRoundTrips()
  {
    const QString  path = m_Work + "/session.json";
    vu::FocalPlane plane = m_Window->GetFocalPlane();
    plane.Layers = 7;
    plane.Filter = "mean";
    m_Window->SetFocalPlane(plane);
    m_Window->SetObjectTransform({ { 1.0, 2.0, 0.0, 10.0, 0.0, 0.0, 1.5 } });
    QVERIFY(m_Window->SaveSession(path));
    vu::WorkbenchWindow reopened;
    reopened.resize(800, 600);
    reopened.show();
    QVERIFY(reopened.OpenSession(path));
    QTRY_VERIFY_WITH_TIMEOUT(!reopened.IsBusy(), 60000);
    QVERIFY2(reopened.GetLastError().isEmpty(), qPrintable(reopened.GetLastError()));
    QCOMPARE(reopened.GetLockedParticles(), m_Window->GetLockedParticles());
    QVERIFY(reopened.GetControls() == m_Window->GetControls());
    QVERIFY(reopened.GetFocalPlane() == m_Window->GetFocalPlane());
    QVERIFY(reopened.GetObjectTransform() == m_Window->GetObjectTransform());
    QCOMPARE(reopened.GetScene().Surface.Points, m_Window->GetScene().Surface.Points);
    QCOMPARE(reopened.GetScene().Surface.Triangles, m_Window->GetScene().Surface.Triangles);
    QCOMPARE(reopened.GetSnapshot().Step, m_Window->GetSnapshot().Step);
    QCOMPARE(reopened.GetSnapshot().Positions, m_Window->GetSnapshot().Positions);
    QVERIFY(reopened.GetTextureVersion() > 0);
    // A damaged session is refused with a message.
    QFile damaged(m_Work + "/damaged.json");
    QVERIFY(damaged.open(QIODevice::WriteOnly));
    damaged.write("{\"format\": \"virtual-unwrap-workbench-session\", \"version\": 1}");
    damaged.close();
    QVERIFY(!reopened.OpenSession(m_Work + "/damaged.json"));
    QVERIFY(!reopened.GetLastError().isEmpty());
  }

  void
  exportWritesTheToolsOutputs()
  {
    m_Window->ResetSimulation();
    const QString folder = m_Work + "/export";
    m_Window->Export(folder);
    WaitIdle(300000);
    QVERIFY2(m_Window->GetLastError().isEmpty(), qPrintable(m_Window->GetLastError()));
    for (const char * name : { "texture.png", "texture.tif", "flat.obj", "surface.vtp", "report.json" })
    {
      QVERIFY2(QFile::exists(folder + "/" + name), name);
    }
    std::ifstream        report((folder + "/report.json").toStdString());
    const nlohmann::json json = nlohmann::json::parse(report);
    QCOMPARE(json.at("parameters").at("simulation").at("locked_particles").get<size_t>(),
             m_Window->GetLockedParticles().size());
  }

  void
  cleanupTestCase()
  {
    m_Window.reset();
  }
};

int
main(int argc, char * argv[])
{
  QSurfaceFormat format = QVTKOpenGLNativeWidget::defaultFormat();
  format.setSamples(0);
  QSurfaceFormat::setDefaultFormat(format);
  QApplication     application(argc, argv);
  WorkbenchGuiTest test;
  return QTest::qExec(&test, argc, argv);
}

#include "vuWorkbenchGuiTest.moc"
