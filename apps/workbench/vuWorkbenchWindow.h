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
#ifndef vuWorkbenchWindow_h
#define vuWorkbenchWindow_h

#include "vuSimulationRunner.h"
#include "vuWorkbenchScene.h"
#include "vuWorkbenchSession.h"

#include <QMainWindow>
#include <QProcess>
#include <QTimer>

#include <vtkActor.h>
#include <vtkCallbackCommand.h>
#include <vtkCellArray.h>
#include <vtkCutter.h>
#include <vtkImageActor.h>
#include <vtkImageData.h>
#include <vtkInteractorStyle.h>
#include <vtkPlane.h>
#include <vtkPolyData.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>
#include <vtkTextActor.h>
#include <vtkTexture.h>
#include <vtkTransform.h>
#include <vtkUnsignedCharArray.h>

#include <functional>
#include <memory>
#include <thread>

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QProgressBar;
class QPushButton;
class QSlider;
class QVBoxLayout;
class QVTKOpenGLNativeWidget;

namespace vu {
class EnergyPlot;

/** The restoration workbench: a person watches the sheet unroll, locks particles, changes
 * the integrator and its parameters while it runs, focuses the layered texture through the
 * sheet, and exports what the command-line tool writes. A thin program over the library:
 * loading and texturing run the module's filters (vuWorkbenchScene), the simulation is
 * itk::MassSpringSheetFlattener on a thread of its own (SimulationRunner), export runs
 * `virtual-unwrap`. Every action of the menus and panels is also a public method, which
 * the scripted tests call. */
class WorkbenchWindow : public QMainWindow
{
  Q_OBJECT

public:
  enum class Interaction
  {
    Camera,
    Lock,
    Release
  };

  explicit WorkbenchWindow(QWidget * parent = nullptr);
  ~WorkbenchWindow() override;

  // Open (in the background, with progress and cancel).
  void
  OpenScan(const QString & path);
  void
  OpenUnwrapOutput(const QString & folder);
  void
  OpenMeshAndVolume(const QString & mesh, const QString & volume);
  bool
  OpenSession(const QString & path);
  bool
  SaveSession(const QString & path);
  /** Writes what `virtual-unwrap unwrap` (or `flatten`, without a scan) writes, with the
   * session's locks, controls and focal plane. */
  void
  Export(const QString & folder);
  void
  CancelWork();
  /** A load, a texture or an export is running. */
  bool
  IsBusy() const;
  bool
  HasSheet() const
  {
    return m_Scene.Surface.GetNumberOfPoints() > 0;
  }
  const Scene &
  GetScene() const
  {
    return m_Scene;
  }
  /** The last error shown (empty after a success). */
  QString
  GetLastError() const
  {
    return m_LastError;
  }
  QString
  GetStatusText() const;

  // Particles.
  void
  SetInteraction(Interaction mode);
  /** Locks or releases the particles seen inside a rectangle of the 3D view (display
   * pixels, origin bottom left, as VTK's events give them); a rectangle of a few pixels is
   * a click and takes the nearest particle. Returns how many changed. */
  size_t
  ApplyRectangle(int x0, int y0, int x1, int y1, bool lock);
  void
  LockEdge(bool outer);
  void
  ReleaseAll();
  void
  SetLocked(const std::vector<uint32_t> & particles, bool lock);
  std::vector<uint32_t>
  GetLockedParticles() const;
  /** Display position (pixels) of a particle in the 3D view. */
  bool
  ProjectParticle(uint32_t particle, double display[2]) const;

  // Simulation.
  void
  StartSimulation();
  void
  SetPaused(bool paused);
  void
  StepSimulation();
  void
  ResetSimulation();
  void
  FlattenNow();
  void
  Wave();
  /** After a divergence: back to the last stable state (paused). */
  bool
  RecoverFromDivergence();
  SimulationControls
  GetControls() const;
  void
  SetControls(const SimulationControls & controls);
  const SimulationSnapshot &
  GetSnapshot() const
  {
    return m_Snapshot;
  }
  /** The flat mesh of the last finished run (or of the opened output). */
  bool
  GetFlatResult(itk::SheetMesh & flat) const;

  // Focal plane and texture.
  FocalPlane
  GetFocalPlane() const;
  void
  SetFocalPlane(const FocalPlane & plane);
  uint64_t
  GetTextureVersion() const
  {
    return m_TextureVersion;
  }
  const TextureImage &
  GetTexture() const
  {
    return m_Texture;
  }

  // Display.
  void
  SetStandardView(int axis, bool positive);
  void
  ResetCamera();
  /** Orthographic (parallel) or perspective projection in the 3D view. */
  void
  SetParallelProjection(bool parallel);
  void
  SetShown(bool texture, bool mesh, bool particles);
  void
  SetObjectTransform(const std::array<double, 7> & transform);
  std::array<double, 7>
  GetObjectTransform() const;
  vtkRenderer *
  GetSheetRenderer() const
  {
    return m_SheetRenderer;
  }
  QVTKOpenGLNativeWidget *
  GetSheetView() const
  {
    return m_SheetView;
  }
  QImage
  GrabSheetView();
  QImage
  GrabFlatView();
  QImage
  GrabSliceView();
  /** Rendered frames of the 3D view per second over the last second. */
  double
  GetFramesPerSecond() const
  {
    return m_FramesPerSecond;
  }
  uint64_t
  GetFramesRendered() const
  {
    return m_Frames;
  }
  /** Puts a sheet into the window directly (for programs that build one). */
  void
  SetScene(const Scene & scene);

private slots:
  void
  Poll();

private:
  void
  BuildWidgets();
  // BuildWidgets' parts, in the order it calls them.
  void
  BuildViews();
  void
  BuildSheetScene();
  void
  BuildSliceScene();
  void
  BuildInteraction();
  void
  BuildControlPanel();
  // The control panel's groups, each added to the panel's layout.
  void
  AddSimulationControls(QVBoxLayout * layout);
  void
  AddParticleControls(QVBoxLayout * layout);
  void
  AddDisplayControls(QVBoxLayout * layout);
  void
  AddObjectControls(QVBoxLayout * layout);
  void
  AddFocalPlaneControls(QVBoxLayout * layout);
  void
  BuildMenus();
  void
  OpenInBackground(const QString & what, std::function<Scene(Job &)> open);
  void
  RunInBackground(const QString & what, std::function<void(Job &)> work, std::function<void()> done);
  void
  ShowError(const QString & message);
  void
  ShowScene();
  void
  UpdateSheetGeometry(const std::vector<double> & positions);
  void
  UpdateLockColours(const std::vector<uint8_t> & locked);
  void
  UpdateSlice();
  void
  RequestTexture();
  void
  ApplyTexture();
  void
  ControlsChanged();
  void
  FocalPlaneChanged();
  void
  RenderAll();
  /** Draws the sheet at full resolution, or (coarse) every n-th row and column of a large
   * grid while it moves. */
  void
  SetDetail(bool coarse);
  Session
  CurrentSession() const;
  const std::vector<double> &
  DisplayedPositions() const;
  void
  OnSelection(vtkObject * caller);

  // Data.
  Scene                m_Scene;
  std::vector<uint8_t> m_Locked; // the locks when no simulation runs
  SimulationRunner     m_Runner;
  SimulationSnapshot   m_Snapshot;
  bool                 m_SimulationStarted{ false };
  bool                 m_HasResume{ false };
  SimulationState      m_Resume;
  itk::SheetMesh       m_Flat;
  TextureImage         m_Texture;
  uint64_t             m_TextureVersion{ 0 };
  bool                 m_TextureWanted{ false };
  QString              m_LastError;
  bool                 m_UpdatingWidgets{ false };

  // Background work: one load/texture job at a time.
  struct Background
  {
    std::thread           Thread;
    std::shared_ptr<Job>  Work;
    std::atomic<bool>     Done{ false };
    std::string           Error;
    std::function<void()> OnDone;
    QString               What;
  };
  std::unique_ptr<Background> m_Background;
  QProcess *                  m_Export{ nullptr };
  QString                     m_ExportFolder;

  // Widgets.
  QVTKOpenGLNativeWidget * m_SheetView{ nullptr };
  QVTKOpenGLNativeWidget * m_FlatView{ nullptr };
  QVTKOpenGLNativeWidget * m_SliceView{ nullptr };
  EnergyPlot *             m_Energy{ nullptr };
  QLabel *                 m_State{ nullptr };
  QLabel *                 m_ErrorBanner{ nullptr };
  QProgressBar *           m_Progress{ nullptr };
  QPushButton *            m_Cancel{ nullptr };
  QComboBox *              m_Integrator{ nullptr };
  QDoubleSpinBox *         m_TimeStep{ nullptr };
  QDoubleSpinBox *         m_Damping{ nullptr };
  QDoubleSpinBox *         m_Stiffness{ nullptr };
  QDoubleSpinBox *         m_Gravity{ nullptr };
  QDoubleSpinBox *         m_Restitution{ nullptr };
  QCheckBox *              m_AutoAdvance{ nullptr };
  QPushButton *            m_Pause{ nullptr };
  QPushButton *            m_Recover{ nullptr };
  QComboBox *              m_Mode{ nullptr };
  QLabel *                 m_LockCount{ nullptr };
  QCheckBox *              m_ShowTexture{ nullptr };
  QCheckBox *              m_ShowMesh{ nullptr };
  QCheckBox *              m_ShowParticles{ nullptr };
  QCheckBox *              m_Parallel{ nullptr };
  QDoubleSpinBox *         m_Transform[7]{};
  QSlider *                m_FocusOffset{ nullptr };
  QSlider *                m_FocusLayers{ nullptr };
  QSlider *                m_FocusSpacing{ nullptr };
  QComboBox *              m_FocusFilter{ nullptr };
  QLabel *                 m_FocusLabel{ nullptr };
  QSlider *                m_SliceIndex{ nullptr };
  QTimer                   m_Timer;

  // VTK.
  vtkSmartPointer<vtkRenderer>        m_SheetRenderer, m_FlatRenderer, m_SliceRenderer;
  vtkSmartPointer<vtkPolyData>        m_SheetData, m_ParticleData, m_FlatData, m_RestData;
  vtkSmartPointer<vtkActor>           m_SurfaceActor, m_MeshActor, m_ParticleActor, m_FlatActor, m_SliceTraceActor;
  vtkSmartPointer<vtkTexture>         m_TextureObject;
  vtkSmartPointer<vtkImageData>       m_TextureImage, m_SliceImage;
  vtkSmartPointer<vtkImageActor>      m_SliceActor;
  vtkSmartPointer<vtkPlane>           m_SlicePlane;
  vtkSmartPointer<vtkCutter>          m_SliceCutter;
  vtkSmartPointer<vtkTransform>       m_ObjectTransform;
  vtkSmartPointer<vtkTextActor>       m_FlatNote;
  vtkSmartPointer<vtkInteractorStyle> m_CameraStyle, m_SelectStyle;
  vtkSmartPointer<vtkCallbackCommand> m_SelectionObserver;
  Interaction                         m_Interaction{ Interaction::Camera };
  vtkSmartPointer<vtkCellArray>       m_FullPolys, m_CoarsePolys, m_FullVerts, m_CoarseVerts;
  std::vector<vtkIdType>              m_CoarseBase; // the particles drawn when coarse (besides the locked)
  bool                                m_Coarse{ false };
  bool                                m_Interacting{ false };
  vtkUnsignedCharArray *              m_ColouredArray{ nullptr }; // the lock flags it shows
  std::vector<uint8_t>                m_ColouredLocks;
  vtkSmartPointer<vtkCallbackCommand> m_InteractionObserver;
  uint64_t                            m_Frames{ 0 };
  uint64_t                            m_FramesAtLastSecond{ 0 };
  double                              m_LastSecond{ 0.0 };
  double                              m_FramesPerSecond{ 0.0 };
  double                              m_SliceWindow[2]{ 0.0, 1.0 };
};
} // namespace vu

#endif
