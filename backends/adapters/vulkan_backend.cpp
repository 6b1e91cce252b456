// The vulkan backend (spec/backends.md R1-BKD-065..069): the frame's T1/T2 impostor pass on
// accel/vulkan's context (a graphics pipeline, or a compute shader), the other passes the
// reference's on the host; the spectral solver's exact kernels on the device and the other epoch
// work the cpu backend's on the host (the reference's bytes). Its 13.1 device is the Vulkan device
// on the same context.
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include "adapters.hpp"
#include "stage_backend.hpp"
#include "r1/accel/vulkan_panel.hpp"
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
  // The spectral solver's inner products and combinations on the device (R1-BKD-069), unless
  // $R1_VULKAN_SPECTRAL=host keeps them on the host's kernels.
  bool spectral_on_device = true;
  if (const char* env = std::getenv("R1_VULKAN_SPECTRAL"); env != nullptr && *env != '\0') {
    const std::string m = env;
    if (m == "host") spectral_on_device = false;
    else if (m != "device") throw std::invalid_argument("R1_VULKAN_SPECTRAL=" + m + ": device or host");
  }
  Q32KernelFactory kernels;
  std::string epoch;
  if (spectral_on_device) {
    auto factory = vk::panel_kernel_factory(state->ctx);
    if (!factory.is_ok()) throw std::invalid_argument(factory.status().message());
    kernels = std::move(factory).value();
    epoch = "the spectral solver's exact inner products and combinations on the device, its operator, focus, encoding and "
            "hierarchy the cpu backend's on the host";
  } else {
#if R1_BACKEND_CPU
    std::string error;
    const accel::cpu::Simd level = accel::cpu::chosen_simd(&error);
    if (!error.empty()) throw std::invalid_argument(error);
    kernels = accel::cpu::kernel_factory(level);
    epoch = "epoch stages the cpu backend's on the host";
#else
    epoch = "epoch stages the reference's with their TBB switches, on the host";
#endif
  }
  ReferenceStages stages(true, false, std::move(kernels));
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
