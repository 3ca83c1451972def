// OSMesa backend: an in-process Mesa context rendering into a small client buffer; all real
// rendering goes to framebuffer objects, so the buffer only has to exist.
#include <GL/osmesa.h>

#include <vector>

#include "common/error.h"
#include "common/gl/backends.h"

namespace canopy::gl {
namespace {

class OsMesaContext final : public Context {
 public:
  OsMesaContext() : Context(Backend::kOsMesa), mBuffer(kSize * kSize * 4) {
    // Newest core profile first; Mesa 22 gives 4.5 on llvmpipe.
    for (const int minor : {5, 3}) {
      const int attributes[] = {OSMESA_FORMAT,
                                OSMESA_RGBA,
                                OSMESA_DEPTH_BITS,
                                24,
                                OSMESA_PROFILE,
                                OSMESA_CORE_PROFILE,
                                OSMESA_CONTEXT_MAJOR_VERSION,
                                4,
                                OSMESA_CONTEXT_MINOR_VERSION,
                                minor,
                                0};
      mContext = OSMesaCreateContextAttribs(attributes, nullptr);
      if (mContext) break;
    }
    if (!mContext) throwInputError("OpenGL backend osmesa: cannot create a 4.3+ core context");
    bind();
    resolveEntryPoints(
        [](const char* name) { return reinterpret_cast<void*>(OSMesaGetProcAddress(name)); });
  }

  ~OsMesaContext() override { OSMesaDestroyContext(mContext); }

 protected:
  void bind() override {
    if (!OSMesaMakeCurrent(mContext, mBuffer.data(), GL_UNSIGNED_BYTE, kSize, kSize)) {
      throwInputError("OpenGL backend osmesa: OSMesaMakeCurrent failed");
    }
  }

 private:
  static constexpr int kSize = 16;
  OSMesaContext mContext = nullptr;
  std::vector<unsigned char> mBuffer;
};

}  // namespace

std::unique_ptr<Context> createOsMesaContext(const ContextOptions&) {
  return std::make_unique<OsMesaContext>();
}

}  // namespace canopy::gl
