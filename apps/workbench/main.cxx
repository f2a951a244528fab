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
// virtual-unwrap-workbench [INPUT]: the restoration workbench. INPUT is a scan (anything
// the command-line tool reads), an output folder of `virtual-unwrap unwrap` or a session
// file (.json); --mesh/--volume open a mesh and its scan. --benchmark-frames measures the
// frame rate while a rolled sheet of that many particles unrolls.
#include "vuWorkbenchWindow.h"

#include "itkSheetPhantomGeometry.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <QApplication>
#include <QElapsedTimer>
#include <QFileInfo>
#include <QSurfaceFormat>
#include <QTimer>
#include <QVTKOpenGLNativeWidget.h>

#include <vtkCamera.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>

#include <cmath>
#include <fstream>
#include <iostream>

namespace {
struct Options
{
  std::string Input, Mesh, Volume, Screenshot, Output, Integrator{ "symplectic-euler" };
  size_t      BenchmarkParticles{ 0 };
  bool        RenderOnly{ false };
  double      Seconds{ 10.0 };
};

// A rolled sheet of about `particles` particles (the phantom geometry's default roll),
// its outer edge locked, unrolling while the camera orbits; frames and steps counted.
int
RunFrameRateBenchmark(vu::WorkbenchWindow & window, const Options & options)
{
  const itk::SheetPhantomGeometry geometry{ itk::SheetPhantomGeometry::Parameters() };
  const double                    area = geometry.GetSheetLength() * geometry.GetSheetWidth();
  vu::Scene                       scene;
  scene.Kind = "mesh+volume";
  scene.Surface = geometry.MakeMidSurfaceMesh(std::sqrt(area / static_cast<double>(options.BenchmarkParticles)));
  window.SetScene(scene);
  window.LockEdge(true);
  vu::SimulationControls controls = window.GetControls();
  controls.Integrator = itk::MassSpringIntegratorFromString(options.Integrator);
  controls.AutoAdvance = false;
  window.SetControls(controls);
  window.SetShown(true, false, true);
  if (!options.RenderOnly)
  {
    window.StartSimulation();
  }
  auto *        timer = new QTimer(&window);
  QElapsedTimer clock; // lives until exec() returns, like the lambda that uses it
  const auto    warmup = 1.0;
  uint64_t      firstFrame = 0, firstStep = 0;
  bool          measuring = false;
  clock.start();
  QObject::connect(timer, &QTimer::timeout, &window, [&, timer] {
    window.GetSheetRenderer()->GetActiveCamera()->Azimuth(2.0);
    window.GetSheetView()->renderWindow()->Render();
    const double t = clock.elapsed() / 1000.0;
    if (!measuring && t >= warmup)
    {
      measuring = true;
      firstFrame = window.GetFramesRendered();
      firstStep = window.GetSnapshot().Step;
      clock.restart();
      return;
    }
    if (measuring && t >= options.Seconds)
    {
      timer->stop();
      const nlohmann::json result = {
        { "particles", scene.Surface.GetNumberOfPoints() },
        { "triangles", scene.Surface.GetNumberOfTriangles() },
        { "integrator", options.RenderOnly ? std::string("none (rendering only)") : options.Integrator },
        { "seconds", t },
        { "frames_per_second", static_cast<double>(window.GetFramesRendered() - firstFrame) / t },
        { "steps_per_second", static_cast<double>(window.GetSnapshot().Step - firstStep) / t },
        { "state", vu::ToString(window.GetSnapshot().State) },
        { "phase", itk::ToString(window.GetSnapshot().Phase) }
      };
      if (options.Output.empty())
      {
        std::cout << result.dump(2) << std::endl;
      }
      else
      {
        std::ofstream(options.Output) << result.dump(2) << std::endl;
      }
      if (!options.Screenshot.empty())
      {
        window.GrabSheetView().save(QString::fromStdString(options.Screenshot));
      }
      QApplication::exit(window.GetSnapshot().State == vu::SimulationSnapshot::Status::Failed ? 1 : 0);
    }
  });
  timer->start(0);
  return QApplication::exec();
}
} // namespace

int
main(int argc, char * argv[])
{
  CLI::App app("The restoration workbench: unroll a sheet by hand, lock particles, focus the texture.");
  Options  options;
  app.add_option("INPUT", options.Input, "a CT scan, an output folder of virtual-unwrap unwrap, or a session (.json)");
  app.add_option("--mesh", options.Mesh, "a sheet mesh to open (with --volume: its scan)");
  app.add_option("--volume", options.Volume, "the scan the mesh lies in");
  app.add_option("--benchmark-frames",
                 options.BenchmarkParticles,
                 "measure the frame rate while a rolled sheet of about this many particles unrolls, print JSON, quit");
  app.add_option("--seconds", options.Seconds, "length of the frame-rate measurement")->check(CLI::PositiveNumber);
  app.add_option("--integrator", options.Integrator, "integrator of the frame-rate measurement");
  app.add_flag("--render-only", options.RenderOnly, "frame-rate measurement without the simulation (the baseline)");
  app.add_option("--output", options.Output, "write the frame-rate measurement here");
  app.add_option("--screenshot", options.Screenshot, "after the measurement, save the 3D view here (PNG)");
  try
  {
    app.parse(argc, argv);
    if (!options.Integrator.empty())
    {
      itk::MassSpringIntegratorFromString(options.Integrator);
    }
  }
  catch (const CLI::ParseError & e)
  {
    return app.exit(e);
  }
  catch (const std::exception & e)
  {
    std::cerr << "virtual-unwrap-workbench: " << e.what() << std::endl;
    return 1;
  }
  QSurfaceFormat format = QVTKOpenGLNativeWidget::defaultFormat();
  format.setSamples(0);
  QSurfaceFormat::setDefaultFormat(format);
  QApplication        application(argc, argv);
  vu::WorkbenchWindow window;
  window.resize(1500, 950);
  window.show();
  if (options.BenchmarkParticles > 0)
  {
    return RunFrameRateBenchmark(window, options);
  }
  if (!options.Mesh.empty())
  {
    window.OpenMeshAndVolume(QString::fromStdString(options.Mesh), QString::fromStdString(options.Volume));
  }
  else if (!options.Input.empty())
  {
    const QFileInfo input(QString::fromStdString(options.Input));
    if (input.suffix() == "json")
    {
      window.OpenSession(input.filePath());
    }
    else if (input.isDir() && QFileInfo(input.filePath() + "/surface.vtp").exists())
    {
      window.OpenUnwrapOutput(input.filePath());
    }
    else
    {
      window.OpenScan(input.filePath());
    }
  }
  return QApplication::exec();
}
