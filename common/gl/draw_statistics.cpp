#include "common/gl/draw_statistics.h"

#include <cassert>
#include <cstring>

namespace canopy::gl {

bool hasGlExtension(const char* name) {
  const Api& g = api();
  GLint count = 0;
  g.GetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i) {
    const auto* extension = reinterpret_cast<const char*>(g.GetStringi(GL_EXTENSIONS, GLuint(i)));
    if (extension && std::strcmp(extension, name) == 0) return true;
  }
  return false;
}

DrawStatistics::DrawStatistics() {
  const bool pipeline = hasGlExtension("GL_ARB_pipeline_statistics_query");
  mTargets[0] = pipeline ? GL_PRIMITIVES_SUBMITTED_ARB : GL_PRIMITIVES_GENERATED;
  mTargets[1] = pipeline ? GL_FRAGMENT_SHADER_INVOCATIONS_ARB : GL_SAMPLES_PASSED;
  mSource = pipeline ? "pipeline_statistics" : "primitives_generated+samples_passed";
  api().GenQueries(2, mQueries);
}

DrawStatistics::~DrawStatistics() {
  if (mQueries[0] != 0) api().DeleteQueries(2, mQueries);
}

void DrawStatistics::begin() {
  assert(!mActive);
  const Api& g = api();
  for (int i = 0; i < 2; ++i) g.BeginQuery(mTargets[i], mQueries[i]);
  mActive = true;
}

DrawCounts DrawStatistics::end() {
  assert(mActive);
  const Api& g = api();
  for (const GLenum target : mTargets) g.EndQuery(target);
  mActive = false;
  GLuint64 values[2] = {0, 0};
  for (int i = 0; i < 2; ++i) g.GetQueryObjectui64v(mQueries[i], GL_QUERY_RESULT, &values[i]);
  return {values[0], values[1]};
}

}  // namespace canopy::gl
