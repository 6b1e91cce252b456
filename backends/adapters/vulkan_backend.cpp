// The vulkan backend (spec/backends.md R1-BKD-065..067): the frame's T1/T2 impostor pass as a
// compute shader on accel/vulkan's context, the other passes the reference's on the host; the
// epoch stages are the cpu backend's on the host (the reference's bytes). Its 13.1 device is the
// Vulkan device on the same context.
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include "adapters.hpp"
#include "stage_backend.hpp"
#include "vulkan_adapters.hpp"
#if R1_BACKEND_CPU
#include "r1/accel/cpu/panel_kernels.hpp"
#endif

namespace r1::backends {

namespace {

struct PassState {
  std::shared_ptr<vk::Context> ctx;
  vk::ImpostorPass impostors;
};

Status draw_on_device(PassState& st, std::span<const render::Impostor> list, const render::View& v, const render::CameraFrame& f,
                      render::OpaqueLayer& layer) {
  vk::ImpostorCamera cam;
  cam.position = v.camera.position;
  cam.right = f.right, cam.up = f.up, cam.forward = f.forward;
  cam.focal_px = f.focal_px;
  cam.width = static_cast<std::uint32_t>(v.width), cam.height = static_cast<std::uint32_t>(v.height);
  std::vector<vk::ImpostorItem> items(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    const render::Impostor& im = list[i];
    items[i] = {im.particle, im.shape, im.center, im.radius, im.color, im.rect.x0, im.rect.y0, im.rect.x1, im.rect.y1};
  }
  return st.impostors.draw(cam, items, layer.t, layer.color, layer.owner);
}

}  // namespace

std::unique_ptr<Backend> make_vulkan_backend() {
  auto ctx = vk::Context::create();
  if (!ctx.is_ok()) throw std::invalid_argument(ctx.status().message());
  auto state = std::make_shared<PassState>();
  state->ctx = std::move(ctx).value();
  // The raster pipeline where the device has one (R1-BKD-068); $R1_VULKAN_IMPOSTORS = compute or
  // raster picks one.
  vk::ImpostorPass::Mode mode = state->ctx->info().graphics ? vk::ImpostorPass::Mode::kRaster : vk::ImpostorPass::Mode::kCompute;
  if (const char* env = std::getenv("R1_VULKAN_IMPOSTORS"); env != nullptr && *env != '\0') {
    const std::string m = env;
    if (m == "compute") mode = vk::ImpostorPass::Mode::kCompute;
    else if (m == "raster" && state->ctx->info().graphics) mode = vk::ImpostorPass::Mode::kRaster;
    else
      throw std::invalid_argument("R1_VULKAN_IMPOSTORS=" + m + ": compute" +
                                  (state->ctx->info().graphics ? " or raster" : " (this device has no graphics queue)"));
  }
  auto pass = vk::ImpostorPass::build(*state->ctx, mode);
  if (!pass.is_ok()) throw std::invalid_argument(pass.status().message());
  state->impostors = std::move(pass).value();
  auto device = make_vulkan_device_on(state->ctx);
  if (!device.is_ok()) throw std::invalid_argument(device.status().message());
  const std::string name = (*device)->describe();
  render::FramePasses passes;
  passes.impostors = [state](std::span<const render::Impostor> list, const render::View& v, const render::CameraFrame& f,
                             render::OpaqueLayer& layer) { return draw_on_device(*state, list, v, f, layer); };
#if R1_BACKEND_CPU
  std::string error;
  const accel::cpu::Simd level = accel::cpu::chosen_simd(&error);
  if (!error.empty()) throw std::invalid_argument(error);
  ReferenceStages stages(true, false, accel::cpu::kernel_factory(level));
  const std::string epoch = "epoch stages the cpu backend's on the host";
#else
  ReferenceStages stages(true, false);
  const std::string epoch = "epoch stages the reference's with their TBB switches, on the host";
#endif
  return std::make_unique<StageBackend>(
      "vulkan",
      "on " + name + ": the T1/T2 impostor pass " +
          (mode == vk::ImpostorPass::Mode::kRaster ? "a graphics pipeline (a quad per impostor, one indirect draw)"
                                                     : "a compute shader over 16-pixel tiles") +
          " ray-casting in fp64 with the reference's intersections; cull, edges, splats, "
          "field, composite and labels the reference's on the host; " + epoch + " (the reference's bytes)",
      std::move(stages), Domain::kFixedQ32, std::move(passes), std::move(device).value());
}

}  // namespace r1::backends
