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
#include "vuWorkbenchWindow.h"

#include "vuEnergyPlot.h"
#include "vuSheetMeshIO.h"

#include <QCheckBox>
#include <QComboBox>
#include <QCoreApplication>
#include <QDir>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFormLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QLabel>
#include <QMenuBar>
#include <QProcessEnvironment>
#include <QProgressBar>
#include <QPushButton>
#include <QScrollArea>
#include <QSlider>
#include <QSplitter>
#include <QStatusBar>
#include <QVBoxLayout>
#include <QVTKOpenGLNativeWidget.h>

#include <vtkActor.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCutter.h>
#include <vtkFloatArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageActor.h>
#include <vtkImageData.h>
#include <vtkImageMapper3D.h>
#include <vtkInteractorStyleRubberBand3D.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkMatrix4x4.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkTexture.h>
#include <vtkTransform.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace vu {
namespace {
double
Now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

const std::vector<std::pair<QString, itk::MassSpringIntegratorEnum>> &
Integrators()
{
  static const std::vector<std::pair<QString, itk::MassSpringIntegratorEnum>> list = {
    { "Euler", itk::MassSpringIntegratorEnum::ExplicitEuler },
    { "Midpoint", itk::MassSpringIntegratorEnum::Midpoint },
    { "Runge-Kutta 4", itk::MassSpringIntegratorEnum::RungeKutta4 },
    { "Symplectic Euler", itk::MassSpringIntegratorEnum::SymplecticEuler },
    { "Implicit Euler", itk::MassSpringIntegratorEnum::ImplicitEuler }
  };
  return list;
}

QDoubleSpinBox *
Spin(double lo, double hi, double value, int decimals, double step, const QString & special = QString())
{
  auto * spin = new QDoubleSpinBox;
  spin->setRange(lo, hi);
  spin->setDecimals(decimals);
  spin->setSingleStep(step);
  spin->setValue(value);
  spin->setKeyboardTracking(false);
  if (!special.isEmpty())
  {
    spin->setSpecialValueText(special);
  }
  return spin;
}

QSlider *
Slider(int lo, int hi, int value)
{
  auto * slider = new QSlider(Qt::Horizontal);
  slider->setRange(lo, hi);
  slider->setValue(value);
  return slider;
}

vtkSmartPointer<vtkPoints>
Points(const std::vector<double> & xyz)
{
  // Single precision: what the graphics card takes, no conversion at every frame.
  auto array = vtkSmartPointer<vtkFloatArray>::New();
  array->SetNumberOfComponents(3);
  array->SetNumberOfTuples(static_cast<vtkIdType>(xyz.size() / 3));
  std::copy(xyz.begin(), xyz.end(), array->GetPointer(0));
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetData(array);
  return points;
}

QImage
Grab(QVTKOpenGLNativeWidget * view)
{
  view->renderWindow()->Render();
  return view->grabFramebuffer();
}
} // namespace

WorkbenchWindow::WorkbenchWindow(QWidget * parent)
  : QMainWindow(parent)
{
  setWindowTitle("VirtualUnwrapping workbench");
  BuildWidgets();
  BuildMenus();
  connect(&m_Timer, &QTimer::timeout, this, &WorkbenchWindow::Poll);
  m_Timer.start(15);
  m_LastSecond = Now();
}

WorkbenchWindow::~WorkbenchWindow()
{
  m_Timer.stop();
  m_Runner.Stop();
  if (m_Background)
  {
    m_Background->Work->Cancel = true;
    if (m_Background->Thread.joinable())
    {
      m_Background->Thread.join();
    }
  }
  if (m_Export != nullptr && m_Export->state() != QProcess::NotRunning)
  {
    m_Export->kill();
    m_Export->waitForFinished(5000);
  }
}

void
WorkbenchWindow::BuildWidgets()
{
  BuildViews();
  BuildSheetScene();
  BuildSliceScene();
  BuildInteraction();
  BuildControlPanel();
}

void
WorkbenchWindow::BuildViews()
{
  // The three views and the energy plot.
  auto makeView = [](vtkSmartPointer<vtkRenderer> & renderer, const double background[3]) {
    auto * view = new QVTKOpenGLNativeWidget;
    auto   window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
    // No multisampling: with software OpenGL (Mesa llvmpipe, the usual case on a
    // workstation without a GPU and under Xvfb) 8 samples cost most of every frame.
    window->SetMultiSamples(0);
    view->setRenderWindow(window);
    renderer = vtkSmartPointer<vtkRenderer>::New();
    renderer->SetBackground(background[0], background[1], background[2]);
    window->AddRenderer(renderer);
    view->setMinimumSize(240, 200);
    return view;
  };
  const double dark[3] = { 0.12, 0.13, 0.16 }, light[3] = { 0.93, 0.93, 0.9 }, black[3] = { 0, 0, 0 };
  m_SheetView = makeView(m_SheetRenderer, dark);
  m_FlatView = makeView(m_FlatRenderer, light);
  m_SliceView = makeView(m_SliceRenderer, black);
  m_Energy = new EnergyPlot;

  auto * top = new QSplitter(Qt::Horizontal);
  top->addWidget(m_SheetView);
  top->addWidget(m_FlatView);
  auto * bottom = new QSplitter(Qt::Horizontal);
  bottom->addWidget(m_SliceView);
  bottom->addWidget(m_Energy);
  auto * views = new QSplitter(Qt::Vertical);
  views->addWidget(top);
  views->addWidget(bottom);
  views->setStretchFactor(0, 3);
  views->setStretchFactor(1, 1);
  views->setSizes({ 600, 250 });
  auto * central = new QWidget;
  auto * centralLayout = new QVBoxLayout(central);
  centralLayout->setContentsMargins(0, 0, 0, 0);
  m_ErrorBanner = new QLabel;
  m_ErrorBanner->setStyleSheet("QLabel { background: #b3261e; color: white; padding: 4px; }");
  m_ErrorBanner->setWordWrap(true);
  m_ErrorBanner->hide();
  centralLayout->addWidget(m_ErrorBanner);
  centralLayout->addWidget(views, 1);
  setCentralWidget(central);
}

void
WorkbenchWindow::BuildSheetScene()
{
  // Sheet pipeline: one point set for the surface, the mesh lines and the particles.
  m_SheetData = vtkSmartPointer<vtkPolyData>::New();
  m_ParticleData = vtkSmartPointer<vtkPolyData>::New();
  m_FlatData = vtkSmartPointer<vtkPolyData>::New();
  m_RestData = vtkSmartPointer<vtkPolyData>::New();
  m_ObjectTransform = vtkSmartPointer<vtkTransform>::New();
  m_TextureObject = vtkSmartPointer<vtkTexture>::New();
  m_TextureObject->InterpolateOn();
  m_TextureImage = vtkSmartPointer<vtkImageData>::New();
  auto actor = [](vtkPolyData * data) {
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputData(data);
    auto a = vtkSmartPointer<vtkActor>::New();
    a->SetMapper(mapper);
    return a;
  };
  m_SurfaceActor = actor(m_SheetData);
  m_SurfaceActor->GetMapper()->ScalarVisibilityOff();
  m_SurfaceActor->GetProperty()->SetColor(0.85, 0.78, 0.62);
  m_MeshActor = actor(m_SheetData);
  m_MeshActor->GetMapper()->ScalarVisibilityOff();
  m_MeshActor->GetProperty()->SetRepresentationToWireframe();
  m_MeshActor->GetProperty()->SetColor(0.35, 0.35, 0.35);
  m_MeshActor->GetProperty()->LightingOff();
  m_MeshActor->SetVisibility(false);
  m_ParticleActor = actor(m_ParticleData);
  m_ParticleActor->GetProperty()->SetPointSize(4.0);
  m_ParticleActor->GetProperty()->LightingOff();
  for (auto * a : { m_SurfaceActor.Get(), m_MeshActor.Get(), m_ParticleActor.Get() })
  {
    a->SetUserTransform(m_ObjectTransform);
    m_SheetRenderer->AddActor(a);
  }
  m_FlatActor = actor(m_FlatData);
  m_FlatActor->GetMapper()->ScalarVisibilityOff();
  m_FlatActor->GetProperty()->SetColor(0.85, 0.78, 0.62);
  m_FlatActor->GetProperty()->LightingOff();
  m_FlatRenderer->AddActor(m_FlatActor);
  m_FlatNote = vtkSmartPointer<vtkTextActor>::New();
  m_FlatNote->SetInput("flat view: open a scan, a mesh or an output folder");
  m_FlatNote->GetTextProperty()->SetColor(0.2, 0.2, 0.2);
  m_FlatNote->GetTextProperty()->SetFontSize(14);
  m_FlatNote->SetDisplayPosition(8, 8);
  m_FlatRenderer->AddActor2D(m_FlatNote);
  m_FlatRenderer->GetActiveCamera()->ParallelProjectionOn();
}

void
WorkbenchWindow::BuildSliceScene()
{
  // Slice view: the scan's slice and the traced sheet in it.
  m_SliceImage = vtkSmartPointer<vtkImageData>::New();
  m_SliceActor = vtkSmartPointer<vtkImageActor>::New();
  m_SliceActor->GetMapper()->SetInputData(m_SliceImage);
  m_SliceActor->SetVisibility(false);
  m_SliceRenderer->AddActor(m_SliceActor);
  m_SlicePlane = vtkSmartPointer<vtkPlane>::New();
  m_SlicePlane->SetNormal(0, 0, 1);
  m_SliceCutter = vtkSmartPointer<vtkCutter>::New();
  m_SliceCutter->SetCutFunction(m_SlicePlane);
  m_SliceCutter->SetInputData(m_RestData);
  auto traceMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  traceMapper->SetInputConnection(m_SliceCutter->GetOutputPort());
  traceMapper->ScalarVisibilityOff();
  m_SliceTraceActor = vtkSmartPointer<vtkActor>::New();
  m_SliceTraceActor->SetMapper(traceMapper);
  m_SliceTraceActor->GetProperty()->SetColor(1.0, 0.85, 0.1);
  m_SliceTraceActor->GetProperty()->SetLineWidth(2.0);
  m_SliceTraceActor->GetProperty()->LightingOff();
  m_SliceTraceActor->SetVisibility(false);
  m_SliceRenderer->AddActor(m_SliceTraceActor);
  m_SliceRenderer->GetActiveCamera()->ParallelProjectionOn();
}

void
WorkbenchWindow::BuildInteraction()
{
  // Interaction: the camera style, and the rubber band for locking (right button rotates,
  // middle pans, wheel zooms there too).
  m_CameraStyle = vtkSmartPointer<vtkInteractorStyleTrackballCamera>::New();
  auto select = vtkSmartPointer<vtkInteractorStyleRubberBand3D>::New();
  m_SelectStyle = select;
  m_SelectionObserver = vtkSmartPointer<vtkCallbackCommand>::New();
  m_SelectionObserver->SetClientData(this);
  m_SelectionObserver->SetCallback([](vtkObject * caller, unsigned long, void * self, void *) {
    static_cast<WorkbenchWindow *>(self)->OnSelection(caller);
  });
  select->AddObserver(vtkCommand::SelectionChangedEvent, m_SelectionObserver);
  m_SheetView->interactor()->SetInteractorStyle(m_CameraStyle);
  // A large sheet is drawn coarser while the camera moves, as while it simulates.
  m_InteractionObserver = vtkSmartPointer<vtkCallbackCommand>::New();
  m_InteractionObserver->SetClientData(this);
  m_InteractionObserver->SetCallback([](vtkObject *, unsigned long event, void * data, void *) {
    auto * self = static_cast<WorkbenchWindow *>(data);
    self->m_Interacting = event == vtkCommand::StartInteractionEvent;
    self->SetDetail(self->m_Interacting || self->m_Snapshot.State == SimulationSnapshot::Status::Running);
    if (!self->m_Interacting)
    {
      self->m_SheetView->renderWindow()->Render();
    }
  });
  for (vtkInteractorStyle * style : { m_CameraStyle.Get(), m_SelectStyle.Get() })
  {
    style->AddObserver(vtkCommand::StartInteractionEvent, m_InteractionObserver);
    style->AddObserver(vtkCommand::EndInteractionEvent, m_InteractionObserver);
  }
  auto frameCounter = vtkSmartPointer<vtkCallbackCommand>::New();
  frameCounter->SetClientData(&m_Frames);
  frameCounter->SetCallback(
    [](vtkObject *, unsigned long, void * frames, void *) { ++*static_cast<uint64_t *>(frames); });
  m_SheetView->renderWindow()->AddObserver(vtkCommand::EndEvent, frameCounter);
}

void
WorkbenchWindow::BuildControlPanel()
{
  // Control panel.
  auto * panel = new QWidget;
  auto * layout = new QVBoxLayout(panel);

  AddSimulationControls(layout);
  AddParticleControls(layout);
  AddDisplayControls(layout);
  AddObjectControls(layout);
  AddFocalPlaneControls(layout);

  auto * sliceBox = new QGroupBox("CT slice");
  auto * sliceLayout = new QVBoxLayout(sliceBox);
  m_SliceIndex = Slider(0, 0, 0);
  connect(m_SliceIndex, &QSlider::valueChanged, this, [this] { UpdateSlice(); });
  sliceLayout->addWidget(m_SliceIndex);
  layout->addWidget(sliceBox);
  layout->addStretch(1);

  auto * scroll = new QScrollArea;
  scroll->setWidget(panel);
  scroll->setWidgetResizable(true);
  auto * dock = new QDockWidget("Controls", this);
  dock->setWidget(scroll);
  dock->setFeatures(QDockWidget::DockWidgetMovable | QDockWidget::DockWidgetFloatable);
  addDockWidget(Qt::RightDockWidgetArea, dock);

  m_Progress = new QProgressBar;
  m_Progress->setRange(0, 1000);
  m_Progress->setMaximumWidth(220);
  m_Progress->hide();
  m_Cancel = new QPushButton("Cancel");
  m_Cancel->hide();
  connect(m_Cancel, &QPushButton::clicked, this, [this] { CancelWork(); });
  statusBar()->addPermanentWidget(m_Progress);
  statusBar()->addPermanentWidget(m_Cancel);
  FocalPlaneChanged();
}

void
WorkbenchWindow::AddSimulationControls(QVBoxLayout * layout)
{
  auto * simulation = new QGroupBox("Simulation");
  auto * form = new QFormLayout(simulation);
  m_Integrator = new QComboBox;
  for (const auto & entry : Integrators())
  {
    m_Integrator->addItem(entry.first);
  }
  m_Integrator->setCurrentIndex(4);
  m_TimeStep = Spin(0.0, 1e3, 0.0, 7, 1e-4, "automatic");
  m_Damping = Spin(-1.0, 1e6, -1.0, 4, 0.1, "automatic");
  m_Stiffness = Spin(0.01, 100.0, 1.0, 3, 0.1);
  m_Gravity = Spin(0.0, 100.0, 1.0, 3, 0.1);
  m_Restitution = Spin(0.0, 1.0, 0.1, 3, 0.05);
  m_AutoAdvance = new QCheckBox("flatten when the sheet hangs still");
  m_AutoAdvance->setChecked(true);
  form->addRow("integrator", m_Integrator);
  form->addRow("time step (s)", m_TimeStep);
  form->addRow("damping (1/s)", m_Damping);
  form->addRow("stiffness x", m_Stiffness);
  form->addRow("gravity x", m_Gravity);
  form->addRow("restitution k_r", m_Restitution);
  form->addRow(m_AutoAdvance);
  auto * buttons = new QGridLayout;
  auto   button = [&](const QString & text, int row, int column, auto slot) {
    auto * b = new QPushButton(text);
    buttons->addWidget(b, row, column);
    connect(b, &QPushButton::clicked, this, slot);
    return b;
  };
  button("Start", 0, 0, [this] { StartSimulation(); });
  m_Pause = button("Pause", 0, 1, [this] { SetPaused(m_Pause->isChecked()); });
  m_Pause->setCheckable(true);
  button("Step", 0, 2, [this] { StepSimulation(); });
  button("Reset", 1, 0, [this] { ResetSimulation(); });
  button("Flatten", 1, 1, [this] { FlattenNow(); });
  button("Wave", 1, 2, [this] { Wave(); });
  m_Recover = button("Back to last stable state", 2, 0, [this] { RecoverFromDivergence(); });
  buttons->addWidget(m_Recover, 2, 0, 1, 3);
  m_Recover->setEnabled(false);
  form->addRow(buttons);
  m_State = new QLabel("no sheet");
  m_State->setWordWrap(true);
  form->addRow(m_State);
  layout->addWidget(simulation);
  for (QDoubleSpinBox * spin : { m_TimeStep, m_Damping, m_Stiffness, m_Gravity, m_Restitution })
  {
    connect(spin, QOverload<double>::of(&QDoubleSpinBox::valueChanged), this, [this] { ControlsChanged(); });
  }
  connect(m_Integrator, QOverload<int>::of(&QComboBox::currentIndexChanged), this, [this] { ControlsChanged(); });
  connect(m_AutoAdvance, &QCheckBox::toggled, this, [this] { ControlsChanged(); });
}

void
WorkbenchWindow::AddParticleControls(QVBoxLayout * layout)
{
  auto * particles = new QGroupBox("Particles");
  auto * particleLayout = new QGridLayout(particles);
  m_Mode = new QComboBox;
  m_Mode->addItems(
    { "camera (left: rotate)", "lock (left: click or rectangle)", "release (left: click or rectangle)" });
  connect(m_Mode, QOverload<int>::of(&QComboBox::currentIndexChanged), this, [this](int index) {
    SetInteraction(static_cast<Interaction>(index));
  });
  particleLayout->addWidget(m_Mode, 0, 0, 1, 3);
  auto * outer = new QPushButton("Lock outer edge");
  auto * inner = new QPushButton("Lock inner edge");
  auto * release = new QPushButton("Release all");
  connect(outer, &QPushButton::clicked, this, [this] { LockEdge(true); });
  connect(inner, &QPushButton::clicked, this, [this] { LockEdge(false); });
  connect(release, &QPushButton::clicked, this, [this] { ReleaseAll(); });
  particleLayout->addWidget(outer, 1, 0);
  particleLayout->addWidget(inner, 1, 1);
  particleLayout->addWidget(release, 1, 2);
  m_LockCount = new QLabel("locked: 0 (red), free: blue");
  particleLayout->addWidget(m_LockCount, 2, 0, 1, 3);
  layout->addWidget(particles);
}

void
WorkbenchWindow::AddDisplayControls(QVBoxLayout * layout)
{
  auto * display = new QGroupBox("Display");
  auto * displayLayout = new QGridLayout(display);
  m_ShowTexture = new QCheckBox("surface (textured)");
  m_ShowMesh = new QCheckBox("mesh");
  m_ShowParticles = new QCheckBox("particles");
  m_ShowTexture->setChecked(true);
  m_ShowParticles->setChecked(true);
  for (QCheckBox * box : { m_ShowTexture, m_ShowMesh, m_ShowParticles })
  {
    connect(box, &QCheckBox::toggled, this, [this] {
      SetShown(m_ShowTexture->isChecked(), m_ShowMesh->isChecked(), m_ShowParticles->isChecked());
    });
  }
  displayLayout->addWidget(m_ShowTexture, 0, 0);
  displayLayout->addWidget(m_ShowMesh, 0, 1);
  displayLayout->addWidget(m_ShowParticles, 0, 2);
  const char * names[] = { "+X", "-X", "+Y", "-Y", "+Z", "-Z" };
  for (int k = 0; k < 6; ++k)
  {
    auto * b = new QPushButton(QString("view ") + names[k]);
    connect(b, &QPushButton::clicked, this, [this, k] { SetStandardView(k / 2, k % 2 == 0); });
    displayLayout->addWidget(b, 1 + k / 3, k % 3);
  }
  auto * reset = new QPushButton("Reset camera");
  connect(reset, &QPushButton::clicked, this, [this] { ResetCamera(); });
  displayLayout->addWidget(reset, 3, 0, 1, 2);
  m_Parallel = new QCheckBox("parallel");
  connect(m_Parallel, &QCheckBox::toggled, this, [this](bool on) { SetParallelProjection(on); });
  displayLayout->addWidget(m_Parallel, 3, 2);
  layout->addWidget(display);
}

void
WorkbenchWindow::AddObjectControls(QVBoxLayout * layout)
{
  auto * object = new QGroupBox("Object (translate mm, rotate degrees, scale)");
  auto * objectLayout = new QGridLayout(object);
  for (int k = 0; k < 7; ++k)
  {
    m_Transform[k] = k < 3   ? Spin(-1e4, 1e4, 0.0, 2, 1.0)
                     : k < 6 ? Spin(-360, 360, 0.0, 1, 5.0)
                             : Spin(0.01, 100, 1.0, 3, 0.1);
    connect(m_Transform[k], QOverload<double>::of(&QDoubleSpinBox::valueChanged), this, [this] {
      if (!m_UpdatingWidgets)
      {
        SetObjectTransform(GetObjectTransform());
      }
    });
    objectLayout->addWidget(m_Transform[k], k / 3, k % 3);
  }
  layout->addWidget(object);
}

void
WorkbenchWindow::AddFocalPlaneControls(QVBoxLayout * layout)
{
  auto * focus = new QGroupBox("Focal plane");
  auto * focusForm = new QFormLayout(focus);
  m_FocusOffset = Slider(-100, 100, 0); // x 0.01 mm
  m_FocusOffset->setObjectName("focal-plane offset");
  m_FocusLayers = Slider(1, 21, 5);  // layers
  m_FocusSpacing = Slider(0, 50, 0); // x 0.01 mm, 0: automatic
  m_FocusFilter = new QComboBox;
  m_FocusFilter->addItems({ "max", "mean", "median", "min" });
  m_FocusLabel = new QLabel;
  focusForm->addRow("offset", m_FocusOffset);
  focusForm->addRow("layers", m_FocusLayers);
  focusForm->addRow("spacing", m_FocusSpacing);
  focusForm->addRow("filter", m_FocusFilter);
  focusForm->addRow(m_FocusLabel);
  for (QSlider * slider : { m_FocusOffset, m_FocusLayers, m_FocusSpacing })
  {
    connect(slider, &QSlider::valueChanged, this, [this] { FocalPlaneChanged(); });
  }
  connect(m_FocusFilter, QOverload<int>::of(&QComboBox::currentIndexChanged), this, [this] { FocalPlaneChanged(); });
  layout->addWidget(focus);
}

void
WorkbenchWindow::BuildMenus()
{
  QMenu * file = menuBar()->addMenu("&File");
  file->addAction("Open &scan...", this, [this] {
    const QString path = QFileDialog::getOpenFileName(
      this, "Open a CT scan", QString(), "Scans (*.mha *.mhd *.nrrd *.nii *.nii.gz *.dcm *.tif *.tiff);;All files (*)");
    if (!path.isEmpty())
    {
      OpenScan(path);
    }
  });
  file->addAction("Open scan &folder (DICOM, TIFF stack)...", this, [this] {
    const QString path = QFileDialog::getExistingDirectory(this, "Open a DICOM series or a TIFF stack");
    if (!path.isEmpty())
    {
      OpenScan(path);
    }
  });
  file->addAction("Open unwrap &output folder...", this, [this] {
    const QString path = QFileDialog::getExistingDirectory(this, "Open an output folder of virtual-unwrap unwrap");
    if (!path.isEmpty())
    {
      OpenUnwrapOutput(path);
    }
  });
  file->addAction("Open &mesh and volume...", this, [this] {
    const QString mesh =
      QFileDialog::getOpenFileName(this, "Sheet mesh", QString(), "Meshes (*.vtp *.obj *.vtk *.off *.stl)");
    if (mesh.isEmpty())
    {
      return;
    }
    const QString volume = QFileDialog::getOpenFileName(this, "Its volume (cancel for none)");
    OpenMeshAndVolume(mesh, volume);
  });
  file->addSeparator();
  file->addAction("Open s&ession...", this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, "Open a session", QString(), "Sessions (*.json)");
    if (!path.isEmpty())
    {
      OpenSession(path);
    }
  });
  file->addAction("Save s&ession...", this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, "Save the session", "session.json", "Sessions (*.json)");
    if (!path.isEmpty())
    {
      SaveSession(path);
    }
  });
  file->addAction("&Export...", this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, "Export into a new folder", "unwrapped");
    if (!path.isEmpty())
    {
      Export(path);
    }
  });
  file->addSeparator();
  file->addAction("&Quit", this, &QWidget::close);
  QMenu * view = menuBar()->addMenu("&View");
  view->addAction("&Reset camera", this, [this] { ResetCamera(); });
}

// ---------------------------------------------------------------------------------------
// Background work

void
WorkbenchWindow::RunInBackground(const QString & what, std::function<void(Job &)> work, std::function<void()> done)
{
  if (m_Background)
  {
    m_Background->Work->Cancel = true;
    if (m_Background->Thread.joinable())
    {
      m_Background->Thread.join();
    }
    m_Background.reset();
  }
  auto background = std::make_unique<Background>();
  background->Work = std::make_shared<Job>();
  background->OnDone = std::move(done);
  background->What = what;
  Background * b = background.get();
  background->Thread = std::thread([b, work] {
    try
    {
      work(*b->Work);
    }
    catch (const itk::ExceptionObject & e)
    {
      b->Error = e.GetDescription();
    }
    catch (const std::exception & e)
    {
      b->Error = e.what();
    }
    b->Done = true;
  });
  m_Background = std::move(background);
  m_Progress->setRange(0, 1000);
  m_Progress->setValue(0);
  m_Progress->show();
  m_Cancel->show();
  statusBar()->showMessage(what);
}

void
WorkbenchWindow::CancelWork()
{
  if (m_Background)
  {
    m_Background->Work->Cancel = true;
  }
  if (m_Export != nullptr && m_Export->state() != QProcess::NotRunning)
  {
    m_Export->kill();
  }
}

bool
WorkbenchWindow::IsBusy() const
{
  return static_cast<bool>(m_Background) || (m_Export != nullptr && m_Export->state() != QProcess::NotRunning);
}

void
WorkbenchWindow::ShowError(const QString & message)
{
  m_LastError = message;
  m_ErrorBanner->setText(message);
  m_ErrorBanner->show();
  statusBar()->showMessage(message);
}

QString
WorkbenchWindow::GetStatusText() const
{
  return m_State->text();
}

void
WorkbenchWindow::OpenInBackground(const QString & what, std::function<Scene(Job &)> open)
{
  auto result = std::make_shared<Scene>();
  RunInBackground(
    "opening " + what, [result, open](Job & job) { *result = open(job); }, [this, result] { SetScene(*result); });
}

void
WorkbenchWindow::OpenScan(const QString & path)
{
  const std::string file = path.toStdString();
  OpenInBackground(path, [file](Job & job) { return vu::OpenScan(file, job); });
}

void
WorkbenchWindow::OpenUnwrapOutput(const QString & folder)
{
  const std::string dir = folder.toStdString();
  OpenInBackground(folder, [dir](Job & job) { return vu::OpenUnwrapOutput(dir, job); });
}

void
WorkbenchWindow::OpenMeshAndVolume(const QString & mesh, const QString & volume)
{
  const std::string m = mesh.toStdString(), v = volume.toStdString();
  OpenInBackground(mesh, [m, v](Job & job) { return vu::OpenMeshAndVolume(m, v, job); });
}

// ---------------------------------------------------------------------------------------
// Scene and display

void
WorkbenchWindow::SetScene(const Scene & scene)
{
  m_Runner.Stop();
  m_Scene = scene;
  m_Locked.assign(m_Scene.Surface.GetNumberOfPoints(), 0);
  m_Flat = m_Scene.Flat;
  m_Snapshot = SimulationSnapshot();
  m_SimulationStarted = false;
  m_HasResume = false;
  m_Energy->Clear();
  m_Texture = TextureImage();
  m_LastError.clear();
  m_ErrorBanner->hide();
  ShowScene();
  ResetCamera();
  RequestTexture();
  QString note = QString("%1 particles").arg(m_Scene.Surface.GetNumberOfPoints());
  for (const auto & w : m_Scene.Warnings)
  {
    note += QString("; ") + QString::fromStdString(w);
  }
  statusBar()->showMessage(note);
}

void
WorkbenchWindow::ShowScene()
{
  const itk::SheetMesh & surface = m_Scene.Surface;
  const size_t           n = surface.GetNumberOfPoints();
  auto                   points = Points(surface.Points);
  m_SheetData->SetPoints(points);
  // The rest shape (cut by the slice view) and the triangles of the moving sheet.
  m_RestData->ShallowCopy(SheetMeshToPolyData(surface));
  m_FullPolys = m_RestData->GetPolys();
  m_SheetData->SetPolys(m_FullPolys);
  m_ParticleData->SetPoints(points);
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  for (vtkIdType i = 0; i < static_cast<vtkIdType>(n); ++i)
  {
    verts->InsertNextCell(1, &i);
  }
  m_FullVerts = verts;
  m_ParticleData->SetVerts(verts);
  // Level of detail for a large grid in motion: every n-th row and column, at most about
  // 50 000 triangles and 25 000 particles (VTK's LOD actors do the same while a view moves).
  m_CoarsePolys = nullptr;
  m_CoarseVerts = nullptr;
  m_CoarseBase.clear();
  m_Coarse = false;
  if (surface.IsGridStructured() && surface.GetNumberOfTriangles() > 60000)
  {
    const int              step = static_cast<int>(std::ceil(std::sqrt(surface.GetNumberOfTriangles() / 50000.0)));
    std::vector<vtkIdType> at(static_cast<size_t>(surface.GridRows) * surface.GridColumns, -1);
    for (size_t i = 0; i < n; ++i)
    {
      at[static_cast<size_t>(surface.GridIndex[2 * i]) * surface.GridColumns + surface.GridIndex[2 * i + 1]] =
        static_cast<vtkIdType>(i);
    }
    auto lines = [&](int count) {
      std::vector<int> kept;
      for (int k = 0; k < count; k += step)
      {
        kept.push_back(k);
      }
      if (kept.back() != count - 1)
      {
        kept.push_back(count - 1);
      }
      return kept;
    };
    const std::vector<int> rows = lines(surface.GridRows), columns = lines(surface.GridColumns);
    m_CoarsePolys = vtkSmartPointer<vtkCellArray>::New();
    m_CoarseVerts = vtkSmartPointer<vtkCellArray>::New();
    auto id = [&](int r, int c) { return at[static_cast<size_t>(r) * surface.GridColumns + c]; };
    for (size_t a = 0; a < rows.size(); ++a)
    {
      for (size_t b = 0; b < columns.size(); ++b)
      {
        const vtkIdType p = id(rows[a], columns[b]);
        if (p >= 0)
        {
          m_CoarseBase.push_back(p);
        }
        if (a + 1 < rows.size() && b + 1 < columns.size())
        {
          const vtkIdType q = id(rows[a], columns[b + 1]), r = id(rows[a + 1], columns[b]),
                          t = id(rows[a + 1], columns[b + 1]);
          if (p >= 0 && q >= 0 && r >= 0 && t >= 0)
          {
            const vtkIdType first[3] = { p, q, t }, second[3] = { p, t, r };
            m_CoarsePolys->InsertNextCell(3, first);
            m_CoarsePolys->InsertNextCell(3, second);
          }
        }
      }
    }
  }
  auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colours->SetNumberOfComponents(3);
  colours->SetNumberOfTuples(static_cast<vtkIdType>(n));
  colours->SetName("lock");
  m_ParticleData->GetPointData()->SetScalars(colours);
  m_ColouredArray = nullptr; // a new array: coloured below whatever the locks
  UpdateLockColours(m_Locked);
  // Flat view: the flat mesh, or the grid's layout before flattening.
  itk::SheetMesh domain;
  if (m_Flat.GetNumberOfPoints() == n && n > 0)
  {
    domain = m_Flat;
    m_FlatNote->SetInput("flat result");
  }
  else if (surface.IsGridStructured())
  {
    domain = surface.ComputeGridLayout();
    m_FlatNote->SetInput("the sheet laid out on its grid (not flattened yet)");
  }
  else
  {
    m_FlatNote->SetInput("not flattened yet");
  }
  m_FlatData->Initialize();
  if (domain.GetNumberOfPoints() > 0)
  {
    m_FlatData->ShallowCopy(SheetMeshToPolyData(domain));
  }
  m_FlatData->Modified();
  m_FlatRenderer->ResetCamera();
  // Slice view.
  if (m_Scene.Volume)
  {
    const auto size = m_Scene.Volume->GetLargestPossibleRegion().GetSize();
    // Display window: 1st to 99.5th percentile of a sample of the voxels.
    const float *      values = m_Scene.Volume->GetBufferPointer();
    const size_t       count = m_Scene.Volume->GetLargestPossibleRegion().GetNumberOfPixels();
    std::vector<float> sample;
    for (size_t k = 0; k < count; k += std::max<size_t>(1, count / 200000))
    {
      if (std::isfinite(values[k]))
      {
        sample.push_back(values[k]);
      }
    }
    if (!sample.empty())
    {
      std::sort(sample.begin(), sample.end());
      m_SliceWindow[0] = sample[sample.size() / 100];
      m_SliceWindow[1] = std::max(m_SliceWindow[0] + 1e-6, double(sample[(995 * sample.size()) / 1000]));
    }
    m_SliceIndex->blockSignals(true);
    m_SliceIndex->setRange(0, static_cast<int>(size[2]) - 1);
    m_SliceIndex->setValue(static_cast<int>(size[2]) / 2);
    m_SliceIndex->blockSignals(false);
  }
  UpdateSlice();
  SetShown(m_ShowTexture->isChecked(), m_ShowMesh->isChecked(), m_ShowParticles->isChecked());
}

const std::vector<double> &
WorkbenchWindow::DisplayedPositions() const
{
  return m_SimulationStarted && m_Snapshot.Positions.size() == m_Scene.Surface.Points.size() ? m_Snapshot.Positions
                                                                                             : m_Scene.Surface.Points;
}

void
WorkbenchWindow::UpdateSheetGeometry(const std::vector<double> & positions)
{
  vtkPoints * points = m_SheetData->GetPoints();
  if (points == nullptr || static_cast<size_t>(points->GetNumberOfPoints()) * 3 != positions.size())
  {
    return;
  }
  auto * array = vtkFloatArray::SafeDownCast(points->GetData());
  std::copy(positions.begin(), positions.end(), array->GetPointer(0));
  points->Modified();
  m_SheetData->Modified();
  m_ParticleData->Modified();
}

void
WorkbenchWindow::UpdateLockColours(const std::vector<uint8_t> & locked)
{
  auto * colours = vtkUnsignedCharArray::SafeDownCast(m_ParticleData->GetPointData()->GetScalars());
  if (colours == nullptr || (colours == m_ColouredArray && locked == m_ColouredLocks))
  {
    return; // every state of a run is shown with its locks; they seldom change
  }
  m_ColouredArray = colours;
  m_ColouredLocks = locked;
  size_t count = 0;
  for (vtkIdType i = 0; i < colours->GetNumberOfTuples(); ++i)
  {
    const bool isLocked = static_cast<size_t>(i) < locked.size() && locked[i] != 0;
    count += isLocked ? 1 : 0;
    const unsigned char red[3] = { 230, 30, 30 }, blue[3] = { 40, 110, 255 };
    colours->SetTypedTuple(i, isLocked ? red : blue);
  }
  colours->Modified();
  m_ParticleData->Modified();
  if (!m_CoarseBase.empty())
  {
    // The coarse particles and every locked one.
    std::vector<uint8_t> drawn(static_cast<size_t>(colours->GetNumberOfTuples()), 0);
    m_CoarseVerts = vtkSmartPointer<vtkCellArray>::New();
    for (vtkIdType id : m_CoarseBase)
    {
      drawn[id] = 1;
      m_CoarseVerts->InsertNextCell(1, &id);
    }
    for (vtkIdType i = 0; i < static_cast<vtkIdType>(locked.size()) && i < colours->GetNumberOfTuples(); ++i)
    {
      if (locked[i] && !drawn[i])
      {
        m_CoarseVerts->InsertNextCell(1, &i);
      }
    }
    if (m_Coarse)
    {
      m_ParticleData->SetVerts(m_CoarseVerts);
    }
  }
  m_LockCount->setText(QString("locked: %1 (red), free: %2 (blue)").arg(count).arg(locked.size() - count));
}

void
WorkbenchWindow::UpdateSlice()
{
  if (!m_Scene.Volume)
  {
    m_SliceActor->SetVisibility(false);
    m_SliceTraceActor->SetVisibility(false);
    m_SliceView->renderWindow()->Render();
    return;
  }
  const auto   size = m_Scene.Volume->GetLargestPossibleRegion().GetSize();
  const auto   spacing = m_Scene.Volume->GetSpacing();
  const auto   origin = m_Scene.Volume->GetOrigin();
  const int    k = std::clamp(m_SliceIndex->value(), 0, static_cast<int>(size[2]) - 1);
  const double z = origin[2] + k * spacing[2];
  m_SliceImage->SetDimensions(static_cast<int>(size[0]), static_cast<int>(size[1]), 1);
  m_SliceImage->SetSpacing(spacing[0], spacing[1], spacing[2]);
  m_SliceImage->SetOrigin(origin[0], origin[1], z);
  m_SliceImage->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto *        out = static_cast<unsigned char *>(m_SliceImage->GetScalarPointer());
  const float * in = m_Scene.Volume->GetBufferPointer() + static_cast<size_t>(k) * size[0] * size[1];
  for (size_t p = 0; p < size[0] * size[1]; ++p)
  {
    const double v = std::isfinite(in[p]) ? (in[p] - m_SliceWindow[0]) / (m_SliceWindow[1] - m_SliceWindow[0]) : 0.0;
    out[p] = static_cast<unsigned char>(std::clamp(v, 0.0, 1.0) * 255.0);
  }
  m_SliceImage->Modified();
  m_SliceActor->SetVisibility(true);
  m_SlicePlane->SetOrigin(0, 0, z);
  m_SliceCutter->Modified();
  m_SliceTraceActor->SetVisibility(true);
  // The trace drawn just in front of the slice.
  m_SliceTraceActor->SetPosition(0, 0, 0.01 * spacing[2]);
  m_SliceRenderer->ResetCamera();
  m_SliceView->renderWindow()->Render();
}

void
WorkbenchWindow::SetShown(bool texture, bool mesh, bool particles)
{
  m_UpdatingWidgets = true;
  m_ShowTexture->setChecked(texture);
  m_ShowMesh->setChecked(mesh);
  m_ShowParticles->setChecked(particles);
  m_UpdatingWidgets = false;
  const bool haveTexture = m_Texture.Width > 0;
  m_SurfaceActor->SetTexture(texture && haveTexture ? m_TextureObject.Get() : nullptr);
  m_SurfaceActor->GetProperty()->SetColor(
    texture && haveTexture ? 1.0 : 0.85, texture && haveTexture ? 1.0 : 0.78, texture && haveTexture ? 1.0 : 0.62);
  m_FlatActor->SetTexture(haveTexture ? m_TextureObject.Get() : nullptr);
  m_FlatActor->GetProperty()->SetColor(haveTexture ? 1.0 : 0.85, haveTexture ? 1.0 : 0.78, haveTexture ? 1.0 : 0.62);
  m_SurfaceActor->SetVisibility(texture);
  m_MeshActor->SetVisibility(mesh);
  m_ParticleActor->SetVisibility(particles);
  RenderAll();
}

void
WorkbenchWindow::SetDetail(bool coarse)
{
  coarse = coarse && m_CoarsePolys != nullptr;
  if (coarse == m_Coarse)
  {
    return;
  }
  m_Coarse = coarse;
  m_SheetData->SetPolys(coarse ? m_CoarsePolys : m_FullPolys);
  m_ParticleData->SetVerts(coarse ? m_CoarseVerts : m_FullVerts);
  m_SheetData->Modified();
  m_ParticleData->Modified();
}

void
WorkbenchWindow::RenderAll()
{
  m_SheetView->renderWindow()->Render();
  m_FlatView->renderWindow()->Render();
}

void
WorkbenchWindow::ResetCamera()
{
  m_SheetRenderer->ResetCamera();
  m_FlatRenderer->ResetCamera();
  RenderAll();
}

void
WorkbenchWindow::SetParallelProjection(bool parallel)
{
  if (m_Parallel->isChecked() != parallel)
  {
    m_Parallel->setChecked(parallel); // comes back here through the signal
    return;
  }
  m_SheetRenderer->GetActiveCamera()->SetParallelProjection(parallel);
  m_SheetRenderer->ResetCamera();
  RenderAll();
}

void
WorkbenchWindow::SetStandardView(int axis, bool positive)
{
  double bounds[6];
  m_SheetRenderer->ComputeVisiblePropBounds(bounds);
  if (!vtkMath::AreBoundsInitialized(bounds))
  {
    return;
  }
  const double centre[3] = { 0.5 * (bounds[0] + bounds[1]),
                             0.5 * (bounds[2] + bounds[3]),
                             0.5 * (bounds[4] + bounds[5]) };
  double       position[3] = { centre[0], centre[1], centre[2] };
  position[axis] += positive ? 1.0 : -1.0;
  vtkCamera * camera = m_SheetRenderer->GetActiveCamera();
  camera->SetFocalPoint(centre);
  camera->SetPosition(position);
  camera->SetViewUp(axis == 2 ? 0.0 : 0.0, axis == 2 ? 1.0 : 0.0, axis == 2 ? 0.0 : 1.0);
  m_SheetRenderer->ResetCamera();
  RenderAll();
}

void
WorkbenchWindow::SetObjectTransform(const std::array<double, 7> & t)
{
  m_UpdatingWidgets = true;
  for (int k = 0; k < 7; ++k)
  {
    m_Transform[k]->setValue(t[k]);
  }
  m_UpdatingWidgets = false;
  // About the sheet's centre: scale, rotate (x, then y, then z), translate.
  double       centre[3] = { 0, 0, 0 };
  const auto & rest = m_Scene.Surface.Points;
  for (size_t i = 0; i < rest.size(); ++i)
  {
    centre[i % 3] += rest[i] / std::max<double>(1.0, rest.size() / 3);
  }
  m_ObjectTransform->Identity();
  m_ObjectTransform->PostMultiply();
  m_ObjectTransform->Translate(-centre[0], -centre[1], -centre[2]);
  m_ObjectTransform->Scale(t[6], t[6], t[6]);
  m_ObjectTransform->RotateX(t[3]);
  m_ObjectTransform->RotateY(t[4]);
  m_ObjectTransform->RotateZ(t[5]);
  m_ObjectTransform->Translate(centre[0] + t[0], centre[1] + t[1], centre[2] + t[2]);
  m_ObjectTransform->Modified();
  RenderAll();
}

std::array<double, 7>
WorkbenchWindow::GetObjectTransform() const
{
  std::array<double, 7> t{};
  for (int k = 0; k < 7; ++k)
  {
    t[k] = m_Transform[k]->value();
  }
  return t;
}

QImage
WorkbenchWindow::GrabSheetView()
{
  return Grab(m_SheetView);
}

QImage
WorkbenchWindow::GrabFlatView()
{
  return Grab(m_FlatView);
}

QImage
WorkbenchWindow::GrabSliceView()
{
  return Grab(m_SliceView);
}

// ---------------------------------------------------------------------------------------
// Particles

void
WorkbenchWindow::SetInteraction(Interaction mode)
{
  m_Interaction = mode;
  if (m_Mode->currentIndex() != static_cast<int>(mode))
  {
    m_Mode->setCurrentIndex(static_cast<int>(mode));
  }
  m_SheetView->interactor()->SetInteractorStyle(mode == Interaction::Camera ? m_CameraStyle : m_SelectStyle);
}

void
WorkbenchWindow::OnSelection(vtkObject * caller)
{
  auto * style = vtkInteractorStyleRubberBand3D::SafeDownCast(caller);
  if (style == nullptr || m_Interaction == Interaction::Camera)
  {
    return;
  }
  const int * a = style->GetStartPosition();
  const int * b = style->GetEndPosition();
  ApplyRectangle(a[0], a[1], b[0], b[1], m_Interaction == Interaction::Lock);
}

bool
WorkbenchWindow::ProjectParticle(uint32_t particle, double display[2]) const
{
  const auto & positions = DisplayedPositions();
  if (3 * static_cast<size_t>(particle) + 2 >= positions.size())
  {
    return false;
  }
  vtkCamera *    camera = m_SheetRenderer->GetActiveCamera();
  vtkMatrix4x4 * projection =
    camera->GetCompositeProjectionTransformMatrix(m_SheetRenderer->GetTiledAspectRatio(), -1, 1);
  vtkNew<vtkMatrix4x4> full;
  vtkMatrix4x4::Multiply4x4(projection, m_ObjectTransform->GetMatrix(), full);
  const double p[4] = { positions[3 * particle], positions[3 * particle + 1], positions[3 * particle + 2], 1.0 };
  double       q[4];
  full->MultiplyPoint(p, q);
  if (q[3] <= 0.0)
  {
    return false;
  }
  const int * size = m_SheetRenderer->GetSize();
  const int * origin = m_SheetRenderer->GetOrigin();
  display[0] = origin[0] + 0.5 * (q[0] / q[3] + 1.0) * size[0];
  display[1] = origin[1] + 0.5 * (q[1] / q[3] + 1.0) * size[1];
  return true;
}

size_t
WorkbenchWindow::ApplyRectangle(int x0, int y0, int x1, int y1, bool lock)
{
  const size_t n = m_Scene.Surface.GetNumberOfPoints();
  if (n == 0)
  {
    return 0;
  }
  const double lowX = std::min(x0, x1), highX = std::max(x0, x1), lowY = std::min(y0, y1), highY = std::max(y0, y1);
  const bool   click = highX - lowX < 3 && highY - lowY < 3;
  std::vector<uint32_t> chosen;
  double                nearest = 10.0; // pixels
  int64_t               nearestId = -1;
  for (uint32_t i = 0; i < n; ++i)
  {
    double d[2];
    if (!ProjectParticle(i, d))
    {
      continue;
    }
    if (click)
    {
      const double distance = std::hypot(d[0] - 0.5 * (lowX + highX), d[1] - 0.5 * (lowY + highY));
      if (distance < nearest)
      {
        nearest = distance;
        nearestId = i;
      }
    }
    else if (d[0] >= lowX && d[0] <= highX && d[1] >= lowY && d[1] <= highY)
    {
      chosen.push_back(i);
    }
  }
  if (click && nearestId >= 0)
  {
    chosen.push_back(static_cast<uint32_t>(nearestId));
  }
  size_t changed = 0;
  for (uint32_t id : chosen)
  {
    changed += m_Locked[id] != (lock ? 1 : 0) ? 1 : 0;
  }
  SetLocked(chosen, lock);
  return changed;
}

void
WorkbenchWindow::SetLocked(const std::vector<uint32_t> & particles, bool lock)
{
  if (!HasSheet())
  {
    return;
  }
  for (uint32_t id : particles)
  {
    if (id < m_Locked.size())
    {
      m_Locked[id] = lock ? 1 : 0;
    }
  }
  if (m_Runner.IsRunning())
  {
    m_Runner.SetLocked(particles, lock);
    std::vector<uint8_t> shown = m_Snapshot.Locked.size() == m_Locked.size() ? m_Snapshot.Locked : m_Locked;
    for (uint32_t id : particles)
    {
      if (id < shown.size())
      {
        shown[id] = lock ? 1 : 0;
      }
    }
    UpdateLockColours(shown);
  }
  else
  {
    UpdateLockColours(m_Locked);
  }
  RenderAll();
}

void
WorkbenchWindow::LockEdge(bool outer)
{
  if (!HasSheet())
  {
    return;
  }
  if (!m_Scene.Surface.IsGridStructured())
  {
    ShowError("locking an edge needs a grid mesh (a traced sheet); lock particles by clicking or by rectangle");
    return;
  }
  SetLocked(itk::MassSpringSheetFlattener::EdgeParticles(
              m_Scene.Surface, outer ? itk::SheetLockedEdgeEnum::OuterEdge : itk::SheetLockedEdgeEnum::InnerEdge),
            true);
}

void
WorkbenchWindow::ReleaseAll()
{
  std::vector<uint32_t> all(m_Locked.size());
  for (size_t i = 0; i < all.size(); ++i)
  {
    all[i] = static_cast<uint32_t>(i);
  }
  SetLocked(all, false);
}

std::vector<uint32_t>
WorkbenchWindow::GetLockedParticles() const
{
  std::vector<uint32_t> ids;
  for (size_t i = 0; i < m_Locked.size(); ++i)
  {
    if (m_Locked[i])
    {
      ids.push_back(static_cast<uint32_t>(i));
    }
  }
  return ids;
}

// ---------------------------------------------------------------------------------------
// Simulation

SimulationControls
WorkbenchWindow::GetControls() const
{
  SimulationControls c;
  c.Integrator = Integrators()[std::max(0, m_Integrator->currentIndex())].second;
  c.TimeStep = m_TimeStep->value();
  c.Damping = m_Damping->value() < 0.0 ? -1.0 : m_Damping->value();
  c.StiffnessScale = m_Stiffness->value();
  c.GravityScale = m_Gravity->value();
  c.Restitution = m_Restitution->value();
  c.AutoAdvance = m_AutoAdvance->isChecked();
  return c;
}

void
WorkbenchWindow::SetControls(const SimulationControls & c)
{
  m_UpdatingWidgets = true;
  for (size_t k = 0; k < Integrators().size(); ++k)
  {
    if (Integrators()[k].second == c.Integrator)
    {
      m_Integrator->setCurrentIndex(static_cast<int>(k));
    }
  }
  m_TimeStep->setValue(c.TimeStep);
  m_Damping->setValue(c.Damping);
  m_Stiffness->setValue(c.StiffnessScale);
  m_Gravity->setValue(c.GravityScale);
  m_Restitution->setValue(c.Restitution);
  m_AutoAdvance->setChecked(c.AutoAdvance);
  m_UpdatingWidgets = false;
  ControlsChanged();
}

void
WorkbenchWindow::ControlsChanged()
{
  if (m_UpdatingWidgets)
  {
    return;
  }
  m_Runner.SetControls(GetControls());
}

void
WorkbenchWindow::StartSimulation()
{
  if (!HasSheet())
  {
    ShowError("nothing to simulate: open a scan, a mesh or an output folder first");
    return;
  }
  if (m_Runner.IsRunning())
  {
    SetPaused(false);
    return;
  }
  m_LastError.clear();
  m_ErrorBanner->hide();
  m_Energy->Clear();
  m_Pause->setChecked(false);
  m_Recover->setEnabled(false);
  itk::MassSpringFlatteningParameters parameters;
  m_Runner.Start(m_Scene.Surface, parameters, m_Locked, GetControls(), false, m_HasResume ? &m_Resume : nullptr);
  m_HasResume = false;
  m_SimulationStarted = true;
}

void
WorkbenchWindow::SetPaused(bool paused)
{
  m_Pause->setChecked(paused);
  m_Runner.SetPaused(paused);
}

void
WorkbenchWindow::StepSimulation()
{
  if (!m_Runner.IsRunning())
  {
    StartSimulation();
  }
  m_Pause->setChecked(true);
  m_Runner.StepOnce();
}

void
WorkbenchWindow::ResetSimulation()
{
  m_Runner.Stop();
  m_SimulationStarted = false;
  m_HasResume = false;
  m_Snapshot = SimulationSnapshot();
  m_Energy->Clear();
  m_Recover->setEnabled(false);
  m_Pause->setChecked(false);
  ShowScene();
  RenderAll();
}

void
WorkbenchWindow::FlattenNow()
{
  if (!m_Runner.IsRunning())
  {
    StartSimulation();
  }
  m_Runner.RequestFlatten();
}

void
WorkbenchWindow::Wave()
{
  if (!m_Runner.IsRunning())
  {
    return;
  }
  m_Runner.Wave(0.3);
}

bool
WorkbenchWindow::RecoverFromDivergence()
{
  if (!m_Runner.ResumeFromStableState())
  {
    ShowError("no stable state to go back to: reset the simulation");
    return false;
  }
  SetControls(m_Runner.GetControls());
  m_Pause->setChecked(true);
  m_Recover->setEnabled(false);
  m_LastError.clear();
  m_ErrorBanner->hide();
  return true;
}

bool
WorkbenchWindow::GetFlatResult(itk::SheetMesh & flat) const
{
  if (m_Flat.GetNumberOfPoints() == 0)
  {
    return false;
  }
  flat = m_Flat;
  return true;
}

// ---------------------------------------------------------------------------------------
// Focal plane and texture

FocalPlane
WorkbenchWindow::GetFocalPlane() const
{
  FocalPlane plane;
  plane.Offset = 0.01 * m_FocusOffset->value();
  plane.Layers = static_cast<unsigned int>(m_FocusLayers->value());
  plane.Spacing = 0.01 * m_FocusSpacing->value();
  plane.Filter = m_FocusFilter->currentText().toStdString();
  return plane;
}

void
WorkbenchWindow::SetFocalPlane(const FocalPlane & plane)
{
  m_UpdatingWidgets = true;
  m_FocusOffset->setValue(static_cast<int>(std::lround(100.0 * plane.Offset)));
  m_FocusLayers->setValue(static_cast<int>(plane.Layers));
  m_FocusSpacing->setValue(static_cast<int>(std::lround(100.0 * plane.Spacing)));
  m_FocusFilter->setCurrentText(QString::fromStdString(plane.Filter));
  m_UpdatingWidgets = false;
  FocalPlaneChanged();
}

void
WorkbenchWindow::FocalPlaneChanged()
{
  const FocalPlane plane = GetFocalPlane();
  m_FocusLabel->setText(
    QString("offset %1 mm, %2 layers, spacing %3, %4")
      .arg(plane.Offset, 0, 'f', 2)
      .arg(plane.Layers)
      .arg(plane.Spacing > 0 ? QString("%1 mm").arg(plane.Spacing, 0, 'f', 2) : QString("automatic"))
      .arg(QString::fromStdString(plane.Filter)));
  if (!m_UpdatingWidgets)
  {
    RequestTexture();
  }
}

void
WorkbenchWindow::RequestTexture()
{
  if (!m_Scene.Volume || !HasSheet())
  {
    return;
  }
  itk::SheetMesh domain;
  if (m_Flat.GetNumberOfPoints() == m_Scene.Surface.GetNumberOfPoints())
  {
    domain = m_Flat;
  }
  else if (m_Scene.Surface.IsGridStructured())
  {
    domain = m_Scene.Surface.ComputeGridLayout();
  }
  else
  {
    return; // no flat domain yet: the texture comes with the flat result
  }
  if (m_Background && m_Background->What != "texture")
  {
    m_TextureWanted = true; // a load is running; the texture follows it
    return;
  }
  m_TextureWanted = false;
  auto        result = std::make_shared<TextureImage>();
  const Scene scene = m_Scene;
  const auto  plane = GetFocalPlane();
  RunInBackground(
    "texture",
    [result, scene, domain, plane](Job & job) { *result = RenderTexture(scene, domain, plane, job); },
    [this, result] {
      m_Texture = *result;
      ApplyTexture();
    });
}

void
WorkbenchWindow::ApplyTexture()
{
  if (m_Texture.Width == 0)
  {
    return;
  }
  m_TextureImage->SetDimensions(static_cast<int>(m_Texture.Width), static_cast<int>(m_Texture.Height), 1);
  m_TextureImage->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  std::copy(
    m_Texture.Pixels.begin(), m_Texture.Pixels.end(), static_cast<unsigned char *>(m_TextureImage->GetScalarPointer()));
  m_TextureImage->Modified();
  m_TextureObject->SetInputData(m_TextureImage);
  auto tcoords = vtkSmartPointer<vtkFloatArray>::New();
  tcoords->SetNumberOfComponents(2);
  tcoords->SetName("texture");
  tcoords->SetNumberOfTuples(static_cast<vtkIdType>(m_Texture.TextureCoordinates.size() / 2));
  std::copy(m_Texture.TextureCoordinates.begin(), m_Texture.TextureCoordinates.end(), tcoords->GetPointer(0));
  if (m_SheetData->GetNumberOfPoints() == tcoords->GetNumberOfTuples())
  {
    m_SheetData->GetPointData()->SetTCoords(tcoords);
  }
  if (m_FlatData->GetNumberOfPoints() == tcoords->GetNumberOfTuples())
  {
    m_FlatData->GetPointData()->SetTCoords(tcoords);
  }
  ++m_TextureVersion;
  SetShown(m_ShowTexture->isChecked(), m_ShowMesh->isChecked(), m_ShowParticles->isChecked());
}

// ---------------------------------------------------------------------------------------
// Polling: background work, the simulation, the frame rate

void
WorkbenchWindow::Poll()
{
  if (m_Background)
  {
    m_Progress->setValue(static_cast<int>(1000.0 * m_Background->Work->Progress));
    if (m_Background->Done)
    {
      m_Background->Thread.join();
      std::unique_ptr<Background> finished = std::move(m_Background);
      m_Progress->hide();
      m_Cancel->hide();
      if (!finished->Error.empty())
      {
        if (!(finished->What == "texture" && finished->Work->Cancel))
        {
          ShowError(finished->What + " failed: " + QString::fromStdString(finished->Error));
        }
      }
      else
      {
        finished->OnDone();
        statusBar()->showMessage(finished->What + ": done", 4000);
      }
      if (m_TextureWanted)
      {
        RequestTexture();
      }
    }
  }
  SimulationSnapshot snapshot;
  if (m_SimulationStarted && m_Runner.GetSnapshot(m_Snapshot.Version, snapshot))
  {
    const bool wasFinished = m_Snapshot.State == SimulationSnapshot::Status::Finished;
    m_Snapshot = std::move(snapshot);
    UpdateSheetGeometry(DisplayedPositions());
    if (m_Snapshot.Locked.size() == m_Locked.size())
    {
      UpdateLockColours(m_Snapshot.Locked);
    }
    if (m_Snapshot.State == SimulationSnapshot::Status::Running ||
        m_Snapshot.State == SimulationSnapshot::Status::Paused)
    {
      m_Energy->Add(m_Snapshot.Step, m_Snapshot.KineticEnergy, m_Snapshot.SpringEnergy);
    }
    if (m_Snapshot.State == SimulationSnapshot::Status::Finished && !wasFinished)
    {
      itk::SheetMesh flat;
      if (m_Runner.GetResult(flat))
      {
        m_Flat = flat;
        m_FlatData->ShallowCopy(SheetMeshToPolyData(flat));
        m_FlatNote->SetInput("flat result");
        m_FlatRenderer->ResetCamera();
        m_FlatView->renderWindow()->Render();
        RequestTexture();
      }
    }
    if (m_Snapshot.State == SimulationSnapshot::Status::Diverged)
    {
      m_Recover->setEnabled(m_Runner.HasStableState());
      ShowError("the simulation diverged (" + QString::fromStdString(m_Snapshot.Message) +
                "); paused: go back to the last stable state, or change the integrator or time step");
    }
    if (m_Snapshot.State == SimulationSnapshot::Status::Failed)
    {
      ShowError("the simulation failed: " + QString::fromStdString(m_Snapshot.Message));
    }
    m_State->setText(QString("%1, %2 phase, step %3, %4 steps/s\n%5, h = %6 s, kinetic %7, spring %8")
                       .arg(ToString(m_Snapshot.State))
                       .arg(itk::ToString(m_Snapshot.Phase))
                       .arg(m_Snapshot.Step)
                       .arg(m_Snapshot.StepsPerSecond, 0, 'f', 0)
                       .arg(itk::ToString(m_Snapshot.Integrator))
                       .arg(m_Snapshot.TimeStep, 0, 'g', 3)
                       .arg(m_Snapshot.KineticEnergy, 0, 'g', 3)
                       .arg(m_Snapshot.SpringEnergy, 0, 'g', 3));
    // The moving sheet only (coarser while it moves, when it is large); the flat view
    // changes when a flat result or a texture comes.
    SetDetail(m_Interacting || m_Snapshot.State == SimulationSnapshot::Status::Running);
    m_SheetView->renderWindow()->Render();
  }
  const double now = Now();
  if (now - m_LastSecond >= 1.0)
  {
    m_FramesPerSecond = static_cast<double>(m_Frames - m_FramesAtLastSecond) / (now - m_LastSecond);
    m_FramesAtLastSecond = m_Frames;
    m_LastSecond = now;
  }
}

// ---------------------------------------------------------------------------------------
// Sessions and export

Session
WorkbenchWindow::CurrentSession() const
{
  Session s;
  s.Source = m_Scene;
  s.Source.Volume = nullptr;
  s.Source.Flat = m_Flat;
  s.Controls = GetControls();
  s.Plane = GetFocalPlane();
  s.Locked = GetLockedParticles();
  if (m_SimulationStarted && m_Snapshot.State != SimulationSnapshot::Status::Finished)
  {
    const SimulationState state = m_Runner.GetCurrentState();
    if (state.Positions.size() == m_Scene.Surface.Points.size())
    {
      s.HasState = true;
      s.State = state;
    }
  }
  else if (m_HasResume)
  {
    s.HasState = true;
    s.State = m_Resume;
  }
  s.ObjectTransform = GetObjectTransform();
  s.HasCamera = true;
  vtkCamera * camera = m_SheetRenderer->GetActiveCamera();
  camera->GetPosition(&s.Camera[0]);
  camera->GetFocalPoint(&s.Camera[3]);
  camera->GetViewUp(&s.Camera[6]);
  return s;
}

bool
WorkbenchWindow::SaveSession(const QString & path)
{
  if (!HasSheet())
  {
    ShowError("nothing to save: no sheet is open");
    return false;
  }
  try
  {
    WriteSession(path.toStdString(), CurrentSession());
  }
  catch (const std::exception & e)
  {
    ShowError(QString("cannot save the session: ") + e.what());
    return false;
  }
  statusBar()->showMessage("session saved to " + path, 4000);
  return true;
}

bool
WorkbenchWindow::OpenSession(const QString & path)
{
  Session session;
  try
  {
    session = ReadSession(path.toStdString());
  }
  catch (const std::exception & e)
  {
    ShowError(e.what());
    return false;
  }
  // The sheet at once; the scan read again in the background (slices, texture).
  Scene scene = session.Source;
  SetScene(scene);
  SetControls(session.Controls);
  SetFocalPlane(session.Plane);
  SetLocked(session.Locked, true);
  SetObjectTransform(session.ObjectTransform);
  if (session.HasState)
  {
    m_HasResume = true;
    m_Resume = session.State;
    m_Resume.Controls = session.Controls;
    m_Snapshot.Positions = session.State.Positions;
    m_Snapshot.Step = session.State.Step;
    m_Snapshot.Phase = session.State.Phase;
    UpdateSheetGeometry(session.State.Positions);
  }
  if (session.HasCamera)
  {
    vtkCamera * camera = m_SheetRenderer->GetActiveCamera();
    camera->SetPosition(&session.Camera[0]);
    camera->SetFocalPoint(&session.Camera[3]);
    camera->SetViewUp(&session.Camera[6]);
    m_SheetRenderer->ResetCameraClippingRange();
  }
  RenderAll();
  if (!scene.ScanPath.empty())
  {
    auto              volume = std::make_shared<WorkbenchVolume::Pointer>();
    const std::string scan = scene.ScanPath;
    RunInBackground(
      "reading " + QString::fromStdString(scan),
      [volume, scan](Job & job) {
        std::vector<std::string> warnings;
        *volume = ReadScanVolume(scan, job, warnings);
      },
      [this, volume] {
        m_Scene.Volume = *volume;
        ShowScene();
        if (m_HasResume)
        {
          UpdateSheetGeometry(m_Resume.Positions);
        }
        RequestTexture();
      });
  }
  return true;
}

void
WorkbenchWindow::Export(const QString & folder)
{
  if (!HasSheet())
  {
    ShowError("nothing to export: no sheet is open");
    return;
  }
  if (m_Export != nullptr && m_Export->state() != QProcess::NotRunning)
  {
    ShowError("an export is already running");
    return;
  }
  const QString tool = QProcessEnvironment::systemEnvironment().value(
    "VU_TOOL", QCoreApplication::applicationDirPath() + "/virtual-unwrap");
  const SimulationControls c = GetControls();
  QStringList              simulation = { "--integrator",  QString(itk::ToString(c.Integrator)),
                                          "--stiffness",   QString::number(c.StiffnessScale, 'g', 17),
                                          "--restitution", QString::number(c.Restitution, 'g', 17),
                                          "--coarsening",  "1" };
  if (c.TimeStep > 0.0)
  {
    simulation << "--time-step" << QString::number(c.TimeStep, 'g', 17);
  }
  if (c.Damping >= 0.0)
  {
    simulation << "--damping" << QString::number(c.Damping, 'g', 17);
  }
  const auto locked = GetLockedParticles();
  if (locked.empty())
  {
    simulation << "--locked-edge"
               << "none";
  }
  QStringList arguments;
  if (!m_Scene.ScanPath.empty() && m_Scene.Kind != "mesh+volume")
  {
    const FocalPlane plane = GetFocalPlane();
    arguments << "unwrap" << QString::fromStdString(m_Scene.ScanPath) << "-o" << folder << "--quiet"
              << "--focus" << QString::number(plane.Offset, 'g', 17) << "--layers" << QString::number(plane.Layers)
              << "--filter" << QString::fromStdString(plane.Filter);
    if (plane.Spacing > 0.0)
    {
      arguments << "--layer-spacing" << QString::number(plane.Spacing, 'g', 17);
    }
  }
  else
  {
    // A mesh without its scan: what `flatten` writes.
    QString mesh = QString::fromStdString(m_Scene.MeshPath);
    if (mesh.isEmpty())
    {
      ShowError("export needs the scan or the mesh file the sheet came from");
      return;
    }
    QDir().mkpath(folder);
    arguments << "flatten" << mesh << "-o" << folder + "/flat.obj"
              << "--report" << folder + "/report.json";
  }
  arguments << simulation;
  if (!locked.empty())
  {
    arguments << "--lock";
    for (uint32_t id : locked)
    {
      arguments << QString::number(id);
    }
  }
  delete m_Export;
  m_Export = new QProcess(this);
  m_ExportFolder = folder;
  connect(m_Export,
          QOverload<int, QProcess::ExitStatus>::of(&QProcess::finished),
          this,
          [this](int code, QProcess::ExitStatus status) {
            m_Progress->hide();
            m_Cancel->hide();
            if (status == QProcess::NormalExit && code == 0)
            {
              m_LastError.clear();
              statusBar()->showMessage("exported to " + m_ExportFolder);
            }
            else
            {
              const QString errors = QString::fromLocal8Bit(m_Export->readAllStandardError()).trimmed();
              ShowError("export failed: " +
                        (errors.isEmpty() ? QString("the tool stopped") : errors.split('\n').last()));
            }
          });
  connect(m_Export, &QProcess::errorOccurred, this, [this, tool](QProcess::ProcessError error) {
    if (error == QProcess::FailedToStart)
    {
      m_Progress->hide();
      m_Cancel->hide();
      ShowError("export failed: cannot run " + tool);
    }
  });
  m_Progress->setRange(0, 0);
  m_Progress->show();
  m_Cancel->show();
  statusBar()->showMessage("exporting to " + folder);
  m_Export->start(tool, arguments);
}
} // namespace vu
