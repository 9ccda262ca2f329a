#include "app/node/node_monitor.h"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <fmt/format.h>
#include <imgui.h>
#include <stb_image_write.h>

#include <chrono>
#include <vector>

#include "core/base/error.h"
#include "core/base/output_path.h"
#include "core/imaging/keyer.h"

namespace lumistage {

namespace {

constexpr int kShrink = 4;  // images shown at a quarter of their size

struct Texture {
  GLuint id = 0;
  int width = 0, height = 0;
  void upload(const std::vector<uint8_t>& rgb, int w, int h) {
    if (id == 0) glGenTextures(1, &id);
    glBindTexture(GL_TEXTURE_2D, id);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, w, h, 0, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
    width = w;
    height = h;
  }
  ImTextureID imgui() const { return reinterpret_cast<ImTextureID>(static_cast<intptr_t>(id)); }
};

// A quarter-size RGB picture of a camera image, whatever its pixel format.
void shrink(const Image& image, std::vector<uint8_t>& rgb, int& w, int& h) {
  w = image.width / kShrink;
  h = image.height / kShrink;
  rgb.resize(size_t(w) * h * 3);
  const ImageView view = image.view();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const Rgb c = colourAt(view, x * kShrink, y * kShrink);
      uint8_t* p = &rgb[(size_t(y) * w + x) * 3];
      p[0] = uint8_t(c.r);
      p[1] = uint8_t(c.g);
      p[2] = uint8_t(c.b);
    }
  }
}

// The low-resolution silhouette (bits, the wire's packing) as white on dark blue.
void silhouetteImage(const SilhouetteMaskData& mask, std::vector<uint8_t>& rgb) {
  rgb.resize(size_t(mask.width) * mask.height * 3);
  for (int i = 0; i < mask.width * mask.height; ++i) {
    const bool on = (mask.bits[i / 8] >> (i % 8)) & 1;
    rgb[3 * i] = on ? 255 : 20;
    rgb[3 * i + 1] = on ? 255 : 30;
    rgb[3 * i + 2] = on ? 255 : 70;
  }
}

// The monitor's window, with ImGui on it, made current. Throws Error without a display.
GLFWwindow* openWindow(const std::string& node_name, int cameras) {
  if (!glfwInit()) {
    throw Error(
        "--monitor: cannot open a window (no display? set DISPLAY, or run without "
        "--monitor)");
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  GLFWwindow* window =
      glfwCreateWindow(std::max(560, 2 * 276 + 40), 90 + cameras * 230,
                       fmt::format("Lumistage node {}", node_name).c_str(), nullptr, nullptr);
  if (!window) {
    glfwTerminate();
    throw Error("--monitor: cannot create an OpenGL 3 window on this display");
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(1);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window, true);
  ImGui_ImplOpenGL3_Init("#version 130");
  return window;
}

// The panel: the node's frame and traffic, its take, and each camera's figures, picture and
// silhouette.
void drawPanel(CameraNode& node, const Rig& rig, const std::string& node_name,
               const CameraNode::MonitorState& state, const std::vector<Texture>& pictures,
               const std::vector<Texture>& silhouettes) {
  const int cameras = static_cast<int>(pictures.size());
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImGui::GetIO().DisplaySize);
  ImGui::Begin(
      "node", nullptr,
      ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings);
  ImGui::Text("node %s: frame %lld, %lld sets sent, %.1f MB", node_name.c_str(),
              static_cast<long long>(state.frame_id), static_cast<long long>(state.sets_sent),
              state.bytes_sent / 1e6);
  if (const TakeStatusData& t = state.take; !t.take.empty()) {
    const ImVec4 colour = !t.error.empty() ? ImVec4(0.95f, 0.3f, 0.3f, 1)
                          : t.finished     ? ImVec4(0.8f, 0.8f, 0.8f, 1)
                                           : ImVec4(0.95f, 0.45f, 0.35f, 1);
    ImGui::TextColored(colour, "take %s: %s, %lld sets written, %lld dropped, %.1f MB %s",
                       t.take.c_str(), t.finished ? "closed" : "recording",
                       static_cast<long long>(t.written), static_cast<long long>(t.dropped),
                       t.bytes / 1e6, t.error.c_str());
  }
  if (state.take.free_bytes >= 0) {
    ImGui::Text("takes' disk: %s free", bytesInWords(state.take.free_bytes).c_str());
  }
  for (int k = 0; k < cameras; ++k) {
    const Camera& camera = rig.camera(node.cameras()[k]);
    ImGui::Separator();
    if (k < static_cast<int>(state.stats.size())) {
      const CameraStats& s = state.stats[k];
      const bool ok = s.last_error.empty() && s.frame_rate_hz > 0;
      ImGui::TextColored(ok ? ImVec4(0.3f, 0.85f, 0.3f, 1) : ImVec4(0.95f, 0.3f, 0.3f, 1),
                         "%s  %.1f fps  %lld frames  %lld dropped  %s", camera.name().c_str(),
                         s.frame_rate_hz, static_cast<long long>(s.frames),
                         static_cast<long long>(s.dropped), s.last_error.c_str());
    }
    const float w = 256, h = 192;
    if (pictures[k].id) {
      ImGui::Image(pictures[k].imgui(), ImVec2(w, h));
    } else {
      ImGui::Dummy(ImVec2(w, h));
    }
    ImGui::SameLine();
    if (silhouettes[k].id) {
      ImGui::Image(silhouettes[k].imgui(), ImVec2(w, h));
    } else {
      ImGui::Dummy(ImVec2(w, h));
    }
  }
  ImGui::End();
}

}  // namespace

void runNodeMonitor(CameraNode& node, const Rig& rig, const std::string& node_name,
                    const std::atomic<bool>& stop, const std::string& screenshot_png) {
  const int cameras = static_cast<int>(node.cameras().size());
  GLFWwindow* window = openWindow(node_name, cameras);
  std::vector<Texture> pictures(cameras), silhouettes(cameras);
  std::vector<uint8_t> rgb;
  auto last_upload = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  int64_t shown_frame = -1;
  CameraNode::MonitorState state;
  std::chrono::steady_clock::time_point all_shown{};
  while (!stop && !glfwWindowShouldClose(window)) {
    glfwPollEvents();
    const auto now = std::chrono::steady_clock::now();
    if (now - last_upload > std::chrono::milliseconds(150)) {
      last_upload = now;
      state = node.monitorState();
      if (state.frame_id != shown_frame) {
        shown_frame = state.frame_id;
        for (int k = 0; k < cameras && k < static_cast<int>(state.frames.size()); ++k) {
          int w = 0, h = 0;
          shrink(state.frames[k]->image, rgb, w, h);
          if (w > 0 && h > 0) pictures[k].upload(rgb, w, h);
        }
        for (const SilhouetteMaskData& mask : state.silhouettes) {
          for (int k = 0; k < cameras; ++k) {
            if (node.cameras()[k] != mask.camera || mask.width <= 0) continue;
            silhouetteImage(mask, rgb);
            silhouettes[k].upload(rgb, mask.width, mask.height);
          }
        }
      }
    }
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    drawPanel(node, rig, node_name, state, pictures, silhouettes);
    ImGui::Render();
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.08f, 0.08f, 0.1f, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (!screenshot_png.empty()) {
      bool all = cameras > 0;
      for (int k = 0; k < cameras; ++k) all = all && pictures[k].id && silhouettes[k].id;
      if (all && all_shown == std::chrono::steady_clock::time_point{}) all_shown = now;
      if (all && now - all_shown > std::chrono::seconds(2)) {
        std::vector<uint8_t> pixels(size_t(fw) * fh * 3);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, fw, fh, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
        stbi_flip_vertically_on_write(1);
        const bool ok = stbi_write_png(screenshot_png.c_str(), fw, fh, 3, pixels.data(), fw * 3);
        fmt::print("{} {}\n", ok ? "saved" : "cannot save", screenshot_png);
        break;
      }
    }
    glfwSwapBuffers(window);
  }
  for (Texture& t : pictures) {
    if (t.id) glDeleteTextures(1, &t.id);
  }
  for (Texture& t : silhouettes) {
    if (t.id) glDeleteTextures(1, &t.id);
  }
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window);
  glfwTerminate();
}

}  // namespace lumistage
