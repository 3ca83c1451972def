#pragma once

#include <cstdint>
#include <string>

#include "common/gl/api.h"

namespace canopy::gl {

// What a span of draws cost the GPU, counted by GL queries.
struct DrawCounts {
  uint64_t primitives = 0;  // primitives submitted (pipeline statistics) or generated
  uint64_t fragments = 0;   // fragment-shader invocations, or samples passed (fallback)

  DrawCounts& operator+=(const DrawCounts& other) {
    primitives += other.primitives;
    fragments += other.fragments;
    return *this;
  }
};

// Counts primitives and fragments between begin() and end() with pipeline-statistics queries
// (GL_ARB_pipeline_statistics_query, core in 4.6: primitives submitted, fragment-shader
// invocations) where the driver has them, else primitives generated and samples passed (which
// miss fragments that fail the depth test or are discarded). source() says which, for meta.json.
// Needs a current context; one begin/end pair at a time.
class DrawStatistics {
 public:
  DrawStatistics();
  ~DrawStatistics();
  DrawStatistics(const DrawStatistics&) = delete;
  DrawStatistics& operator=(const DrawStatistics&) = delete;

  // "pipeline_statistics" or "primitives_generated+samples_passed".
  const std::string& source() const { return mSource; }
  void begin();
  DrawCounts end();  // waits for the results

 private:
  GLuint mQueries[2] = {0, 0};
  GLenum mTargets[2] = {0, 0};
  std::string mSource;
  bool mActive = false;
};

// Whether the current context has the extension (GL_NUM_EXTENSIONS / glGetStringi).
bool hasGlExtension(const char* name);

}  // namespace canopy::gl
