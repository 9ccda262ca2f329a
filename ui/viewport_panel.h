#pragma once

#include <QElapsedTimer>
#include <QImage>
#include <QPoint>
#include <QWidget>
#include <memory>
#include <optional>

#include "core/geometry/rig.h"
#include "core/render/camera_path.h"
#include "core/render/clone_set.h"
#include "core/render/orbit_view.h"
#include "ui/pipeline_panel.h"

class QCheckBox;
class QComboBox;
class QLabel;
class QPushButton;
class QSlider;
class QTimer;

namespace lumistage {

// What the viewport draws over the live rendering.
struct ViewportLayers {
  bool image = true;  // the pipeline's blended view (the lumigraph rendering)
  bool mesh = false;  // the placed body's surface, shaded
  bool wireframe = false;
  bool skeleton = true;
  bool frusta = true;  // the input cameras
  bool floor = true;   // the stage floor, a 0.5 m grid
};

// The free-viewpoint viewport: the pipeline's rendering for the director's virtual camera with
// overlays drawn from the same camera. Left drag orbits, right or middle drag pans, the wheel
// zooms; with Shift a left drag moves the clone under the cursor on the floor, with Ctrl it turns
// it. Every change of the view is sent on (viewChanged) for the nodes to render. It paints on a
// QOpenGLWidget where the platform has OpenGL on a GPU, on a plain widget otherwise (OpenGL on
// the CPU, Qt's offscreen platform for tests, LUMISTAGE_VIEWPORT_RASTER set).
class ViewportWidget : public QWidget {
  Q_OBJECT

 public:
  explicit ViewportWidget(CloneSet* clones, QWidget* parent = nullptr);
  bool usesOpenGL() const { return uses_gl_; }
  // Paints the scene (called by the canvas): drawn with Qt's raster engine into an image, redrawn
  // only after refresh(), then put on the canvas.
  void paintTo(QPainter& painter, int width, int height);
  void paintScene(QPainter& painter, int width, int height);

  OrbitView& view() { return view_; }
  const OrbitView& view() const { return view_; }
  void setView(const OrbitView& view);
  ViewportLayers& layers() { return layers_; }
  void setRig(const Rig& rig, const StageBox& stage);  // stage: the rig's (stageVolume)
  void showSnapshot(const PipelineSnapshot& snapshot);
  // A new blended frame and the body placed for it (every frame, between snapshots).
  void showView(const PipelineView& view);
  int64_t viewsShown() const { return views_shown_; }
  // The size the nodes render (and a recording records) the view at: renderWidth() wide, the
  // widget's aspect.
  QSize renderSize() const;
  int renderWidth() const { return render_width_; }
  void setRenderWidth(int width);  // 160 to 1920; the nodes render at it from the next frame
  // The view for the nodes to render, with the clones (drawn by the lumigraph with the
  // captured texture).
  ViewData viewData() const;
  // Where the actor stands now (the placed body's root on the floor), for clones.
  Eigen::Vector3d actorFloorPoint() const;
  const PipelineSnapshot& snapshot() const { return snapshot_; }

 public slots:
  void refresh();  // repaints

 signals:
  void viewChanged();
  void clonesChanged();

 protected:
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;

 private:
  QWidget* canvas_;
  bool uses_gl_ = false;
  QImage frame_;
  bool dirty_ = true;
  OrbitView view_ = OrbitView::studioDefault();
  ViewportLayers layers_;
  Rig rig_;
  StageBox stage_;  // the rig's (stageVolume), outlined on the floor
  PipelineSnapshot snapshot_;
  int64_t views_shown_ = 0;  // new blended frames drawn
  int render_width_ = 640;
  CloneSet* clones_;
  QPoint last_mouse_;
  Qt::MouseButton dragging_ = Qt::NoButton;
  std::optional<int> dragged_clone_;
  bool turning_clone_ = false;
};

// The viewport with its controls: layer toggles, snap to an input camera, and a camera path on a
// timeline (keyframes of the view, played back).
class ViewportPanel : public QWidget {
  Q_OBJECT

 public:
  explicit ViewportPanel(CloneSet* clones, QWidget* parent = nullptr);

  ViewportWidget* viewport() const { return viewport_; }
  void setRig(const Rig& rig, const StageBox& stage);
  // Commands, as the controls do them:
  bool snapToCamera(int camera);  // false for an unknown camera
  void addKey();                  // the current view at the timeline's time
  bool removeKey();               // the key at the timeline's time
  void play(bool on);
  void setTime(double time_s);
  double time() const { return time_s_; }
  const CameraPath& path() const { return path_; }
  bool playing() const;
  // Writes the pipeline's current view (the blended image, without overlays) to `file` (PNG or
  // JPEG by its name), atomically. False with `error` set, nothing written, before the first
  // frame or when the file cannot be written.
  bool saveImage(const QString& file, QString* error = nullptr);
  // The choices of the view's size (ViewportWidget::setRenderWidth), widths in pixels.
  static constexpr int kRenderWidths[] = {320, 640, 960, 1280};
  QComboBox* sizeChoice() const { return size_; }
  // As the Record button: on asks for recording to `file` (recordingRequested), off stops it.
  void record(bool on, const QString& file = {});
  bool recording() const;
  // The recording ended elsewhere (a failed write, the pipeline stopped): the button goes up.
  void recordingEnded();

 signals:
  void viewChanged(const lumistage::ViewData& view);
  void recordingRequested(const QString& file);
  void recordingStopped();

 private:
  void refreshTimeline();

  ViewportWidget* viewport_;
  QComboBox* snap_;
  QComboBox* size_;  // the view's size
  QSlider* timeline_;
  QLabel* time_label_;
  QPushButton* play_;
  QPushButton* record_;
  QTimer* player_;
  QElapsedTimer played_;      // since Play path started: the path follows the clock, not the ticks
  double played_from_s_ = 0;  // the path's time when it started
  CameraPath path_;
  double time_s_ = 0;
  Rig rig_;
};

}  // namespace lumistage

Q_DECLARE_METATYPE(lumistage::ViewData)
