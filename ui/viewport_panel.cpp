#include "ui/viewport_panel.h"

#include <QBuffer>
#include <QComboBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QGuiApplication>
#include <QHBoxLayout>
#include <QLabel>
#include <QMenu>
#include <QMessageBox>
#include <QMouseEvent>
#include <QOffscreenSurface>
#include <QOpenGLContext>
#include <QOpenGLWidget>
#include <QPainter>
#include <QPainterPath>
#include <QPushButton>
#include <QSlider>
#include <QTimer>
#include <QToolButton>
#include <QVBoxLayout>
#include <QWheelEvent>
#include <algorithm>
#include <cmath>

#include "core/base/atomic_file.h"
#include "core/render/egl_context.h"
#include "ui/stage_plan_view.h"

namespace lumistage {

namespace {

constexpr double kTimelineLength_s = 20.0;

std::optional<QPointF> projectTo(const Camera& camera, const Eigen::Vector3d& p) {
  const Eigen::Vector3d c = camera.toCamera(p);
  if (c.z() < 0.05) return std::nullopt;  // behind or at the eye
  const std::optional<Eigen::Vector2d> px = camera.project(p);
  if (!px) return std::nullopt;
  return QPointF(px->x() + 0.5, px->y() + 0.5);
}

void drawSegment(QPainter& painter, const Camera& camera, const Eigen::Vector3d& a,
                 const Eigen::Vector3d& b) {
  const auto pa = projectTo(camera, a), pb = projectTo(camera, b);
  if (pa && pb) painter.drawLine(*pa, *pb);
}

// The placed body's surface moved by `transform`, flat-shaded from a light at the eye, far
// triangles first.
void drawMesh(QPainter& painter, const Camera& camera, const TriangleMesh& mesh,
              const Eigen::Affine3d& transform, const QColor& colour, bool fill, bool wire) {
  const int n = mesh.vertexCount();
  std::vector<std::optional<QPointF>> px(n);
  std::vector<Eigen::Vector3d> world(n);
  for (int v = 0; v < n; ++v) {
    world[v] = transform * mesh.positions.col(v).cast<double>();
    px[v] = projectTo(camera, world[v]);
  }
  struct Face {
    double depth;
    int t;
    double shade;
  };
  std::vector<Face> faces;
  faces.reserve(mesh.triangles.size());
  const Eigen::Vector3d eye = camera.centre();
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    if (!px[tri[0]] || !px[tri[1]] || !px[tri[2]]) continue;
    const Eigen::Vector3d centre = (world[tri[0]] + world[tri[1]] + world[tri[2]]) / 3;
    const Eigen::Vector3d normal =
        (world[tri[1]] - world[tri[0]]).cross(world[tri[2]] - world[tri[0]]).normalized();
    const Eigen::Vector3d to_eye = (eye - centre).normalized();
    const double facing = normal.dot(to_eye);
    if (fill && facing <= 0) continue;  // back faces
    faces.push_back({(centre - eye).norm(), static_cast<int>(t), std::max(0.0, facing)});
  }
  std::sort(faces.begin(), faces.end(),
            [](const Face& a, const Face& b) { return a.depth > b.depth; });
  painter.setPen(wire ? QPen(colour.lighter(130), 0.6) : Qt::NoPen);
  for (const Face& f : faces) {
    const Eigen::Vector3i& tri = mesh.triangles[f.t];
    const QPointF points[3] = {*px[tri[0]], *px[tri[1]], *px[tri[2]]};
    if (fill) {
      const double k = 0.35 + 0.65 * f.shade;
      painter.setBrush(QColor(int(colour.red() * k), int(colour.green() * k),
                              int(colour.blue() * k), colour.alpha()));
    } else {
      painter.setBrush(Qt::NoBrush);
    }
    painter.drawPolygon(points, 3);
  }
}

// The surfaces the viewport paints on; mouse events pass through to the viewport.
class GlCanvas : public QOpenGLWidget {
 public:
  explicit GlCanvas(ViewportWidget* owner) : QOpenGLWidget(owner), owner_(owner) {}

 protected:
  void paintGL() override {
    QPainter painter(this);
    owner_->paintTo(painter, width(), height());
  }

 private:
  ViewportWidget* owner_;
};

// Whether OpenGL renders on the CPU here (Mesa's llvmpipe or softpipe: no GPU, a VM, a remote
// desktop). A QOpenGLWidget makes Qt compose the whole window through OpenGL at every repaint of
// any of its widgets: in the demo on this project's 2-core machine that took the studio 0.2 of a
// core (llvmpipe's threads) and the pipeline from 11 to 8 frames a second. The scene is painted
// with Qt's raster engine either way.
bool openGLOnTheCpu() {
  static const bool on_cpu = [] {
    QOffscreenSurface surface;
    surface.create();
    QOpenGLContext context;
    if (!context.create() || !context.makeCurrent(&surface)) return true;  // no OpenGL at all
    // GLVND dispatches to Qt's current context as to the renderer's EGL one.
    const bool software = currentRendererIsSoftware();
    context.doneCurrent();
    return software;
  }();
  return on_cpu;
}

class RasterCanvas : public QWidget {
 public:
  explicit RasterCanvas(ViewportWidget* owner) : QWidget(owner), owner_(owner) {}

 protected:
  void paintEvent(QPaintEvent*) override {
    QPainter painter(this);
    owner_->paintTo(painter, width(), height());
  }

 private:
  ViewportWidget* owner_;
};

}  // namespace

ViewportWidget::ViewportWidget(CloneSet* clones, QWidget* parent)
    : QWidget(parent), clones_(clones) {
  uses_gl_ = QGuiApplication::platformName() != "offscreen" &&
             qEnvironmentVariableIsEmpty("LUMISTAGE_VIEWPORT_RASTER") && !openGLOnTheCpu();
  canvas_ = uses_gl_ ? static_cast<QWidget*>(new GlCanvas(this)) : new RasterCanvas(this);
  canvas_->setAttribute(Qt::WA_TransparentForMouseEvents);
  setMinimumSize(320, 180);  // the window fits a 1366x768 laptop screen
  setMouseTracking(false);
  setFocusPolicy(Qt::StrongFocus);
  setToolTip(
      tr("Drag: orbit. Right or middle drag: pan. Wheel: zoom. Shift+drag: move a clone; "
         "Ctrl+drag: turn it."));
}

void ViewportWidget::setView(const OrbitView& view) {
  view_ = view;
  refresh();
  emit viewChanged();
}

void ViewportWidget::setRenderWidth(int width) {
  render_width_ = std::clamp(width, 160, 1920) / 2 * 2;
  emit viewChanged();
}

QSize ViewportWidget::renderSize() const {
  const int w = render_width_;
  const double aspect = width() > 0 && height() > 0 ? double(height()) / width() : 0.75;
  int h = static_cast<int>(std::lround(w * std::clamp(aspect, 0.4, 1.5) / 2) * 2);
  return {w, h};
}

void ViewportWidget::resizeEvent(QResizeEvent*) {
  canvas_->setGeometry(rect());
  emit viewChanged();  // the nodes render at the new aspect
}

void ViewportWidget::refresh() {
  dirty_ = true;
  canvas_->update();
}

void ViewportWidget::paintTo(QPainter& painter, int w, int h) {
  const QSize size(std::max(1, w), std::max(1, h));
  if (dirty_ || frame_.size() != size) {
    // Redrawn over the last picture: a new image only when the size changes.
    if (frame_.size() != size) frame_ = QImage(size, QImage::Format_ARGB32_Premultiplied);
    QPainter raster(&frame_);
    paintScene(raster, w, h);
    dirty_ = false;
  }
  painter.drawImage(0, 0, frame_);
}

ViewData ViewportWidget::viewData() const {
  ViewData data = toViewData(view_.pose(), renderSize().width(), renderSize().height());
  if (clones_) {
    for (const Clone& c : clones_->clones()) {
      data.clones.push_back(float(c.offset_m.x()));
      data.clones.push_back(float(c.offset_m.y()));
      data.clones.push_back(float(c.yaw_rad));
    }
  }
  return data;
}

Eigen::Vector3d ViewportWidget::actorFloorPoint() const {
  if (snapshot_.joints.empty()) return Eigen::Vector3d::Zero();
  return Eigen::Vector3d(snapshot_.joints[0].x(), snapshot_.joints[0].y(), 0);
}

void ViewportWidget::showSnapshot(const PipelineSnapshot& snapshot) {
  if (snapshot.view_frame != snapshot_.view_frame) ++views_shown_;
  snapshot_ = snapshot;
  refresh();
}

void ViewportWidget::showView(const PipelineView& view) {
  if (view.view_frame == snapshot_.view_frame) return;
  ++views_shown_;
  static_cast<PipelineView&>(snapshot_) = view;
  refresh();
}

void ViewportWidget::setRig(const Rig& rig, const StageBox& stage) {
  rig_ = rig;
  stage_ = stage;
  refresh();
}

void ViewportWidget::paintScene(QPainter& painter, int w, int h) {
  painter.setRenderHint(QPainter::Antialiasing);
  painter.setRenderHint(QPainter::SmoothPixmapTransform);
  const QRect area(0, 0, w, h);
  painter.fillRect(area, QColor(24, 26, 30));
  const Camera camera = view_.camera(std::max(1, w), std::max(1, h));
  if (layers_.floor) {
    // Half-metre lines over at least 6 x 6 m, and over the whole stage.
    painter.setPen(QPen(QColor(90, 96, 104), 1));
    const Eigen::Array2d lo = (2 * stage_.lower.head<2>().array()).floor().min(-6.0) / 2,
                         hi = (2 * stage_.upper.head<2>().array()).ceil().max(6.0) / 2;
    for (double x = lo.x(); x <= hi.x() + 1e-9; x += 0.5)
      drawSegment(painter, camera, {x, lo.y(), 0}, {x, hi.y(), 0});
    for (double y = lo.y(); y <= hi.y() + 1e-9; y += 0.5)
      drawSegment(painter, camera, {lo.x(), y, 0}, {hi.x(), y, 0});
    painter.setPen(QPen(QColor(40, 180, 90), 2));  // the stage the actor is tracked on
    const Eigen::Vector3d& a = stage_.lower;
    const Eigen::Vector3d& b = stage_.upper;
    const Eigen::Vector3d c[4] = {
        {a.x(), a.y(), 0}, {b.x(), a.y(), 0}, {b.x(), b.y(), 0}, {a.x(), b.y(), 0}};
    for (int k = 0; k < 4; ++k) drawSegment(painter, camera, c[k], c[(k + 1) % 4]);
  }
  if (layers_.image && !snapshot_.view.isNull()) {
    painter.drawImage(area, snapshot_.view);
  }
  if (layers_.frusta) {
    for (int i = 0; i < rig_.cameraCount(); ++i) {
      const Camera& input = rig_.camera(i);
      const std::optional<int> node = rig_.findNode(input.node());
      painter.setPen(QPen(StagePlanView::nodeColour(node.value_or(0)), 1.5));
      const Eigen::Vector3d o = input.centre();
      const double depth = 0.35;
      Eigen::Vector3d corners[4];
      const Eigen::Vector2d px[4] = {{0, 0},
                                     {input.width() - 1.0, 0},
                                     {input.width() - 1.0, input.height() - 1.0},
                                     {0, input.height() - 1.0}};
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector2d n = input.pixelToNormalized(px[k]);
        corners[k] = o + input.rotation().transpose() * (Eigen::Vector3d(n.x(), n.y(), 1) * depth);
      }
      for (int k = 0; k < 4; ++k) {
        drawSegment(painter, camera, o, corners[k]);
        drawSegment(painter, camera, corners[k], corners[(k + 1) % 4]);
      }
      if (const auto label = projectTo(camera, o)) {
        painter.drawText(*label + QPointF(4, -4), QString::fromStdString(input.name()));
      }
    }
  }
  if (snapshot_.mesh && (layers_.mesh || layers_.wireframe)) {
    drawMesh(painter, camera, *snapshot_.mesh, Eigen::Affine3d::Identity(),
             QColor(200, 180, 160, layers_.mesh ? 150 : 255), layers_.mesh, layers_.wireframe);
  }
  // Clones: copies of the placed body, moved.
  if (clones_ && snapshot_.mesh) {
    const Eigen::Vector3d actor = actorFloorPoint();
    for (const Clone& clone : clones_->clones()) {
      // The clone's transform acts about the actor's place: move there, turn, shift.
      const Eigen::Affine3d t = clone.transform(actor);
      // The pipeline's image shows the clones with the captured texture; without it, the mesh.
      if (snapshot_.view.isNull())
        drawMesh(painter, camera, *snapshot_.mesh, t, QColor(120, 170, 230, 230), true, false);
      if (const auto p = projectTo(camera, t * actor)) {
        painter.setPen(QColor(120, 170, 230));
        painter.drawText(*p + QPointF(6, 14), QString::fromStdString(clone.name));
      }
    }
  }
  if (layers_.skeleton && snapshot_.joints.size() == snapshot_.parents.size()) {
    painter.setPen(QPen(QColor(255, 210, 40), 2.5));
    for (size_t j = 0; j < snapshot_.joints.size(); ++j) {
      if (snapshot_.parents[j] >= 0)
        drawSegment(painter, camera, snapshot_.joints[j], snapshot_.joints[snapshot_.parents[j]]);
    }
    painter.setBrush(QColor(255, 120, 40));
    for (const Eigen::Vector3d& j : snapshot_.joints) {
      if (const auto p = projectTo(camera, j)) painter.drawEllipse(*p, 3, 3);
    }
  }
  painter.setPen(QColor(220, 220, 220));
  QString caption = tr("eye (%1, %2, %3) m, %4 m from the target")
                        .arg(view_.eye().x(), 0, 'f', 1)
                        .arg(view_.eye().y(), 0, 'f', 1)
                        .arg(view_.eye().z(), 0, 'f', 1)
                        .arg(view_.distance(), 0, 'f', 1);
  if (snapshot_.view.isNull()) caption += tr("  -  waiting for the pipeline's first frame");
  painter.drawText(QRect(8, h - 24, w - 16, 20), Qt::AlignLeft, caption);
  if (!snapshot_.recording.isEmpty()) {
    painter.setPen(Qt::NoPen);
    painter.setBrush(QColor(230, 40, 40));
    painter.drawEllipse(QPoint(16, 16), 6, 6);
    painter.setPen(QColor(255, 120, 120));
    painter.drawText(QRect(28, 6, w - 36, 20), Qt::AlignLeft | Qt::AlignVCenter,
                     tr("REC  %1  -  %2 frames")
                         .arg(QFileInfo(snapshot_.recording).fileName())
                         .arg(snapshot_.recorded_frames));
  }
}

void ViewportWidget::mousePressEvent(QMouseEvent* event) {
  last_mouse_ = event->position().toPoint();
  dragging_ = event->button();
  dragged_clone_.reset();
  turning_clone_ = false;
  if (clones_ && event->button() == Qt::LeftButton &&
      (event->modifiers() & (Qt::ShiftModifier | Qt::ControlModifier))) {
    const Camera camera = view_.camera(width(), height());
    dragged_clone_ = clones_->pick(camera, Eigen::Vector2d(last_mouse_.x(), last_mouse_.y()),
                                   actorFloorPoint(), 60);
    turning_clone_ = event->modifiers() & Qt::ControlModifier;
  }
}

void ViewportWidget::mouseMoveEvent(QMouseEvent* event) {
  const QPoint p = event->position().toPoint();
  const QPoint d = p - last_mouse_;
  if (dragging_ == Qt::NoButton) return;
  if (dragged_clone_) {
    if (turning_clone_) {
      clones_->rotateBy(*dragged_clone_, d.x() * 0.02);
    } else {
      const Camera camera = view_.camera(width(), height());
      const auto a = camera.unproject(Eigen::Vector2d(last_mouse_.x(), last_mouse_.y()));
      const auto b = camera.unproject(Eigen::Vector2d(p.x(), p.y()));
      const auto fa = a ? floorPoint(*a) : std::nullopt;
      const auto fb = b ? floorPoint(*b) : std::nullopt;
      if (fa && fb) clones_->moveBy(*dragged_clone_, (*fb - *fa).head<2>());
    }
    last_mouse_ = p;
    refresh();
    emit clonesChanged();
    emit viewChanged();  // the nodes draw the clones
    return;
  }
  if (dragging_ == Qt::LeftButton) {
    view_.dragOrbit(d.x(), d.y(), height());
  } else {
    view_.dragPan(d.x(), d.y(), height());
  }
  last_mouse_ = p;
  refresh();
  emit viewChanged();
}

void ViewportWidget::mouseReleaseEvent(QMouseEvent*) {
  dragging_ = Qt::NoButton;
  dragged_clone_.reset();
}

void ViewportWidget::wheelEvent(QWheelEvent* event) {
  view_.wheelZoom(event->angleDelta().y() / 120.0);
  refresh();
  emit viewChanged();
}

ViewportPanel::ViewportPanel(CloneSet* clones, QWidget* parent)
    : QWidget(parent),
      viewport_(new ViewportWidget(clones, this)),
      snap_(new QComboBox(this)),
      size_(new QComboBox(this)),
      timeline_(new QSlider(Qt::Horizontal, this)),
      time_label_(new QLabel(this)),
      play_(new QPushButton(tr("Play path"), this)),
      record_(new QPushButton(tr("Record"), this)),
      player_(new QTimer(this)) {
  auto* layers = new QHBoxLayout;
  // What the viewport draws, in one menu (six check boxes made the window 1555 px wide at least).
  auto* layer_button = new QToolButton(this);
  layer_button->setText(tr("Layers"));
  layer_button->setObjectName("layers");
  layer_button->setToolTip(tr("What the viewport draws over the view"));
  layer_button->setPopupMode(QToolButton::InstantPopup);
  layer_button->setToolButtonStyle(Qt::ToolButtonTextOnly);
  auto* layer_menu = new QMenu(layer_button);
  layer_button->setMenu(layer_menu);
  layers->addWidget(layer_button);
  auto toggle = [&](const QString& name, bool ViewportLayers::*layer) {
    QAction* action = layer_menu->addAction(name);
    action->setCheckable(true);
    action->setChecked(viewport_->layers().*layer);
    connect(action, &QAction::toggled, this, [this, layer](bool on) {
      viewport_->layers().*layer = on;
      viewport_->refresh();
    });
  };
  toggle(tr("Image"), &ViewportLayers::image);
  toggle(tr("Mesh"), &ViewportLayers::mesh);
  toggle(tr("Wireframe"), &ViewportLayers::wireframe);
  toggle(tr("Skeleton"), &ViewportLayers::skeleton);
  toggle(tr("Frusta"), &ViewportLayers::frusta);
  toggle(tr("Floor"), &ViewportLayers::floor);
  layers->addStretch(1);
  auto* reset = new QPushButton(tr("Reset view"), this);
  layers->addWidget(reset);
  layers->addWidget(snap_);
  snap_->addItem(tr("Snap to camera..."));
  // How large the nodes render the view: sharper, or cheaper for them (and the recording's size).
  for (int width : kRenderWidths) {
    size_->addItem(tr("%1 wide").arg(width), width);
    if (width == viewport_->renderWidth()) size_->setCurrentIndex(size_->count() - 1);
  }
  size_->setToolTip(
      tr("The size the nodes render the view at (and a recording records): "
         "larger is sharper and costs the nodes more"));
  layers->addWidget(size_);
  connect(size_, &QComboBox::currentIndexChanged, this,
          [this](int index) { viewport_->setRenderWidth(size_->itemData(index).toInt()); });
  auto* save = new QPushButton(tr("Save image..."), this);
  save->setToolTip(tr("Write the pipeline's current view (without overlays) as PNG or JPEG"));
  record_->setCheckable(true);
  record_->setToolTip(
      tr("Record every frame of this view to a video (.mp4, H.264; or .avi, Motion-JPEG)"));
  layers->addWidget(save);
  layers->addWidget(record_);
  connect(save, &QPushButton::clicked, this, [this] {
    const QString file = QFileDialog::getSaveFileName(this, tr("Save the view"), "view.png",
                                                      tr("Images (*.png *.jpg)"));
    QString error;
    if (!file.isEmpty() && !saveImage(file, &error))
      QMessageBox::warning(this, tr("Save the view"), error);
  });
  connect(record_, &QPushButton::clicked, this, [this](bool on) {
    QString file;
    if (on) {
      // The suffix is added by the dialog, before it asks whether to replace a file of that name.
      QFileDialog dialog(this, tr("Record the view"), "view.mp4",
                         tr("H.264 video (*.mp4);;Motion-JPEG video (*.avi)"));
      dialog.setAcceptMode(QFileDialog::AcceptSave);
      dialog.setDefaultSuffix("mp4");
      connect(&dialog, &QFileDialog::filterSelected, &dialog, [&dialog](const QString& filter) {
        dialog.setDefaultSuffix(filter.contains("*.avi") ? "avi" : "mp4");
      });
      if (dialog.exec() == QDialog::Accepted && !dialog.selectedFiles().isEmpty())
        file = dialog.selectedFiles().front();
      // Another suffix typed: the chosen kind's is added, a name the dialog did not check.
      const QString suffix = QFileInfo(file).suffix().toLower();
      if (!file.isEmpty() && suffix != "mp4" && suffix != "avi") {
        file += "." + dialog.defaultSuffix();
        if (QFileInfo::exists(file) &&
            QMessageBox::question(this, tr("Record the view"),
                                  tr("%1 already exists. Replace it?").arg(file)) !=
                QMessageBox::Yes)
          file.clear();
      }
      if (file.isEmpty()) {
        record_->setChecked(false);
        return;
      }
    }
    record(on, file);
  });
  connect(reset, &QPushButton::clicked, this,
          [this] { viewport_->setView(OrbitView::studioDefault()); });
  connect(snap_, &QComboBox::activated, this, [this](int index) {
    if (index > 0) snapToCamera(index - 1);
    snap_->setCurrentIndex(0);
  });

  auto* path = new QHBoxLayout;
  auto* key = new QPushButton(tr("Key"), this);
  key->setToolTip(tr("Keyframe the current view at this time"));
  auto* unkey = new QPushButton(tr("Delete key"), this);
  path->addWidget(new QLabel(tr("Camera path:"), this));
  path->addWidget(key);
  path->addWidget(unkey);
  path->addWidget(play_);
  path->addWidget(timeline_, 1);
  path->addWidget(time_label_);
  timeline_->setRange(0, static_cast<int>(kTimelineLength_s * 10));
  play_->setCheckable(true);
  play_->setObjectName("play_path");
  timeline_->setObjectName("timeline");
  connect(key, &QPushButton::clicked, this, &ViewportPanel::addKey);
  connect(unkey, &QPushButton::clicked, this, &ViewportPanel::removeKey);
  connect(play_, &QPushButton::toggled, this, &ViewportPanel::play);
  // Any move of the handle (dragged, a click in the groove, keys, the wheel) moves the time;
  // refreshTimeline() sets it without a signal.
  connect(timeline_, &QSlider::valueChanged, this, [this](int v) { setTime(v / 10.0); });
  connect(player_, &QTimer::timeout, this, [this] {
    const double next = played_from_s_ + played_.elapsed() / 1000.0;
    if (next >= path_.duration()) {
      setTime(path_.duration());  // ends exactly on the last key
      play(false);
      return;
    }
    setTime(next);
  });

  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  layout->addLayout(layers);
  layout->addWidget(viewport_, 1);
  layout->addLayout(path);
  connect(viewport_, &ViewportWidget::viewChanged, this,
          [this] { emit viewChanged(viewport_->viewData()); });
  refreshTimeline();
}

bool ViewportPanel::saveImage(const QString& file, QString* error) {
  const QImage& view = viewport_->snapshot().view;
  auto fail = [&](const QString& why) {
    if (error) *error = file + ": " + why;
    return false;
  };
  if (view.isNull()) return fail(tr("no view yet: start the pipeline"));
  const QByteArray format = file.toLower().endsWith(".jpg") || file.toLower().endsWith(".jpeg")
                                ? QByteArray("JPG")
                                : QByteArray("PNG");
  QByteArray bytes;
  QBuffer buffer(&bytes);
  buffer.open(QIODevice::WriteOnly);
  if (!view.save(&buffer, format.constData())) return fail(tr("cannot encode the image"));
  try {
    writeFileAtomically(file.toStdString(), std::string_view(bytes.constData(), bytes.size()));
  } catch (const std::exception& e) {
    return fail(QString::fromStdString(e.what()));
  }
  return true;
}

void ViewportPanel::record(bool on, const QString& file) {
  record_->setChecked(on);
  if (on) {
    emit recordingRequested(file);
  } else {
    emit recordingStopped();
  }
}

bool ViewportPanel::recording() const {
  return record_->isChecked();
}

void ViewportPanel::recordingEnded() {
  record_->setChecked(false);
}

void ViewportPanel::setRig(const Rig& rig, const StageBox& stage) {
  rig_ = rig;
  viewport_->setRig(rig, stage);
  while (snap_->count() > 1) snap_->removeItem(1);
  for (const Camera& c : rig.cameras()) snap_->addItem(QString::fromStdString(c.name()));
}

bool ViewportPanel::snapToCamera(int camera) {
  if (camera < 0 || camera >= rig_.cameraCount()) return false;
  viewport_->setView(OrbitView::fromCamera(rig_.camera(camera)));
  return true;
}

void ViewportPanel::addKey() {
  path_.setKey(time_s_, viewport_->view().pose());
  refreshTimeline();
}

bool ViewportPanel::removeKey() {
  const bool removed = path_.removeKey(time_s_, 0.25);
  refreshTimeline();
  return removed;
}

bool ViewportPanel::playing() const {
  return player_->isActive();
}

void ViewportPanel::play(bool on) {
  if (on && path_.keys().size() >= 2) {
    if (time_s_ >= path_.duration()) setTime(0);
    played_from_s_ = time_s_;
    played_.start();
    player_->start(40);
  } else {
    player_->stop();
  }
  const QSignalBlocker block(play_);
  play_->setChecked(player_->isActive());
}

void ViewportPanel::setTime(double time_s) {
  time_s_ = std::clamp(time_s, 0.0, kTimelineLength_s);
  if (path_.keys().size() >= 1) {
    viewport_->setView(OrbitView::fromPose(path_.at(time_s_), viewport_->view().distance()));
  }
  refreshTimeline();
}

void ViewportPanel::refreshTimeline() {
  const QSignalBlocker block(timeline_);
  timeline_->setValue(static_cast<int>(std::lround(time_s_ * 10)));
  QStringList keys;
  for (const CameraKey& k : path_.keys()) keys << QString::number(k.time_s, 'f', 1);
  time_label_->setText(tr("%1 s  (keys: %2)")
                           .arg(time_s_, 0, 'f', 1)
                           .arg(keys.isEmpty() ? tr("none") : keys.join(", ")));
  // A path needs two keys: until then the button says so instead of doing nothing.
  const bool playable = path_.keys().size() >= 2;
  play_->setEnabled(playable);
  play_->setToolTip(playable ? QString() : tr("Set two keys or more (Key) to play a path"));
}

}  // namespace lumistage
