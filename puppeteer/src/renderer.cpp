// OpenGL 3.3 core rendering of the live app: shaders (as raw strings), buffer uploads, draw calls, read-back.
#include "renderer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <algorithm>
#include <cstddef>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace imps::app {
namespace {

// sRGB encoding shared by every fragment shader: the framebuffer holds sRGB bytes, the maths is in linear light.
#define IMPS_GLSL_SRGB                                                                      \
  "vec3 srgb(vec3 c) {\n"                                                                   \
  "  c = clamp(c, 0.0, 1.0);\n"                                                             \
  "  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));\n" \
  "}\n"

const char* const kMeshVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec3 aColor;
uniform mat4 uView;
uniform mat4 uProjection;
out vec3 vNormal;
out vec3 vColor;
out vec3 vViewPosition;
void main() {
  vec4 p = uView * vec4(aPosition, 1.0);
  vViewPosition = p.xyz;
  vNormal = mat3(uView) * aNormal;
  vColor = aColor;
  gl_Position = uProjection * p;
}
)";

const char* const kMeshFragment = "#version 330 core\n" IMPS_GLSL_SRGB R"(
in vec3 vNormal;
in vec3 vColor;
in vec3 vViewPosition;
uniform vec3 uLight;      // towards the light, camera space, unit
uniform float uAmbient;
uniform float uRim;
uniform int uHasNormals;
out vec4 fragColor;
void main() {
  vec3 faceNormal = normalize(cross(dFdx(vViewPosition), dFdy(vViewPosition)));
  vec3 n = uHasNormals != 0 ? vNormal : faceNormal;
  float len = length(n);
  n = len > 0.0 ? n / len : faceNormal;
  vec3 toEye = -vViewPosition;
  if (dot(n, toEye) < 0.0) n = -n;  // two-sided: back faces lit as if they faced the camera
  float diffuse = max(dot(n, uLight), 0.0);
  float rim = pow(1.0 - clamp(n.z, 0.0, 1.0), 3.0);
  vec3 c = vColor * (uAmbient + (1.0 - uAmbient) * diffuse) + vec3(uRim * rim);
  fragColor = vec4(srgb(c), 1.0);
}
)";

const char* const kPointVertex = R"(#version 330 core
layout(location = 0) in vec3 aPosition;
uniform mat4 uView;
uniform mat4 uProjection;
uniform float uPointSize;
void main() {
  gl_Position = uProjection * (uView * vec4(aPosition, 1.0));
  gl_Position.z -= 0.0005 * gl_Position.w;  // in front of the surface the particle sits on
  gl_PointSize = uPointSize;
}
)";

const char* const kPointFragment = R"(#version 330 core
out vec4 fragColor;
void main() {
  vec2 d = gl_PointCoord - vec2(0.5);
  if (dot(d, d) > 0.25) discard;  // round dots
  fragColor = vec4(1.0, 0.95, 0.35, 1.0);
}
)";

// The background: a quad covering the viewport whose two bottom and two top corners carry the gradient's end
// colours already sRGB-encoded, so the fragment shader only passes the interpolated colour on. Under a software
// rasterizer (llvmpipe) encoding every pixel cost ~4 ms of a 1280x720 frame; now the pass costs about what a clear
// does. Interpolating encoded colours instead of linear ones differs by at most 2/255 over this gradient.
const char* const kBackgroundVertex = "#version 330 core\n" IMPS_GLSL_SRGB R"(
uniform vec3 uTop;
uniform vec3 uBottom;
out vec3 vColor;
void main() {
  // A triangle strip of four corners from the vertex index alone: (-1,-1), (1,-1), (-1,1), (1,1).
  vec2 p = vec2(float(gl_VertexID & 1), float(gl_VertexID >> 1)) * 2.0 - 1.0;
  vColor = srgb(p.y > 0.0 ? uTop : uBottom);
  gl_Position = vec4(p, 0.0, 1.0);
}
)";

const char* const kBackgroundFragment = R"(#version 330 core
in vec3 vColor;
out vec4 fragColor;
void main() { fragColor = vec4(vColor, 1.0); }
)";

// The overlay: window-pixel positions, colours in linear light.
const char* const kOverlayVertex = "#version 330 core\n" IMPS_GLSL_SRGB R"(
layout(location = 0) in vec2 aPixel;
layout(location = 1) in vec3 aColor;
uniform vec2 uWindow;
out vec3 vColor;
void main() {
  vColor = srgb(aColor);
  gl_Position = vec4(aPixel.x / uWindow.x * 2.0 - 1.0, 1.0 - aPixel.y / uWindow.y * 2.0, 0.0, 1.0);
}
)";

// Compiles and links one program; returns 0 and appends to `error` on failure.
GLuint buildProgram(const char* vertex, const char* fragment, const char* name, std::string& error) {
  auto compile = [&](GLenum type, const char* source) -> GLuint {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[2048] = {};
      glGetShaderInfoLog(s, sizeof log, nullptr, log);
      error += std::string(name) + (type == GL_VERTEX_SHADER ? " vertex" : " fragment") + " shader: " + log;
      glDeleteShader(s);
      return 0;
    }
    return s;
  };
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex), fs = compile(GL_FRAGMENT_SHADER, fragment);
  if (!vs || !fs) {
    if (vs) glDeleteShader(vs);
    if (fs) glDeleteShader(fs);
    return 0;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    error += std::string(name) + " program: " + log;
    glDeleteProgram(program);
    return 0;
  }
  return program;
}

// Orphans `buffer` (a fresh store of `bytes`) and fills it, so the GPU may still read last frame's store.
void orphanAndFill(GLenum target, GLuint buffer, const void* data, size_t bytes) {
  glBindBuffer(target, buffer);
  glBufferData(target, static_cast<GLsizeiptr>(bytes), nullptr, GL_STREAM_DRAW);
  if (bytes > 0) glBufferSubData(target, 0, static_cast<GLsizeiptr>(bytes), data);
}

void setMatrices(GLuint program, const glm::mat4& view, const glm::mat4& projection) {
  glUniformMatrix4fv(glGetUniformLocation(program, "uView"), 1, GL_FALSE, glm::value_ptr(view));
  glUniformMatrix4fv(glGetUniformLocation(program, "uProjection"), 1, GL_FALSE, glm::value_ptr(projection));
}

}  // namespace

Renderer::Renderer() {
  meshProgram_ = buildProgram(kMeshVertex, kMeshFragment, "mesh", error_);
  pointProgram_ = buildProgram(kPointVertex, kPointFragment, "particle", error_);
  backgroundProgram_ = buildProgram(kBackgroundVertex, kBackgroundFragment, "background", error_);
  overlayProgram_ = buildProgram(kOverlayVertex, kBackgroundFragment, "overlay", error_);
  glGenVertexArrays(1, &overlayVao_);
  glGenBuffers(1, &overlayBuffer_);
  glBindVertexArray(overlayVao_);
  glBindBuffer(GL_ARRAY_BUFFER, overlayBuffer_);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex),
                        reinterpret_cast<const void*>(offsetof(OverlayVertex, pixel)));
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(OverlayVertex),
                        reinterpret_cast<const void*>(offsetof(OverlayVertex, color)));
  glEnableVertexAttribArray(0);
  glEnableVertexAttribArray(1);
  glGenVertexArrays(1, &meshVao_);
  glGenVertexArrays(1, &pointVao_);
  glGenVertexArrays(1, &backgroundVao_);
  GLuint buffers[5];
  glGenBuffers(5, buffers);
  positionBuffer_ = buffers[0], normalBuffer_ = buffers[1], colorBuffer_ = buffers[2];
  indexBuffer_ = buffers[3], pointBuffer_ = buffers[4];

  glBindVertexArray(meshVao_);
  const GLuint attributeBuffers[3] = {positionBuffer_, normalBuffer_, colorBuffer_};
  for (GLuint a = 0; a < 3; ++a) {
    glBindBuffer(GL_ARRAY_BUFFER, attributeBuffers[a]);
    glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glEnableVertexAttribArray(0);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, indexBuffer_);  // recorded in the VAO
  glBindVertexArray(pointVao_);
  glBindBuffer(GL_ARRAY_BUFFER, pointBuffer_);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glEnableVertexAttribArray(0);
  glBindVertexArray(0);
}

Renderer::~Renderer() {
  const GLuint buffers[5] = {positionBuffer_, normalBuffer_, colorBuffer_, indexBuffer_, pointBuffer_};
  glDeleteBuffers(5, buffers);
  const GLuint arrays[3] = {meshVao_, pointVao_, backgroundVao_};
  glDeleteVertexArrays(3, arrays);
  glDeleteBuffers(1, &overlayBuffer_);
  glDeleteVertexArrays(1, &overlayVao_);
  for (GLuint p : {meshProgram_, pointProgram_, backgroundProgram_, overlayProgram_})
    if (p) glDeleteProgram(p);
}

void Renderer::uploadMesh(const Mesh& mesh) {
  glBindVertexArray(meshVao_);
  orphanAndFill(GL_ARRAY_BUFFER, positionBuffer_, mesh.positions.data(), mesh.positions.size() * sizeof(float));
  meshHasNormals_ = !mesh.normals.empty();
  meshHasColors_ = !mesh.colors.empty();
  if (meshHasNormals_) {
    orphanAndFill(GL_ARRAY_BUFFER, normalBuffer_, mesh.normals.data(), mesh.normals.size() * sizeof(float));
    glEnableVertexAttribArray(1);
  } else {
    glDisableVertexAttribArray(1);
  }
  if (meshHasColors_) {
    orphanAndFill(GL_ARRAY_BUFFER, colorBuffer_, mesh.colors.data(), mesh.colors.size() * sizeof(float));
    glEnableVertexAttribArray(2);
  } else {
    glDisableVertexAttribArray(2);
  }
  orphanAndFill(GL_ELEMENT_ARRAY_BUFFER, indexBuffer_, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  indexCount_ = static_cast<int32_t>(mesh.indices.size());
  glBindVertexArray(0);
}

void Renderer::uploadParticles(std::span<const glm::vec3> positions) {
  orphanAndFill(GL_ARRAY_BUFFER, pointBuffer_, positions.data(), positions.size_bytes());
  pointCount_ = static_cast<int32_t>(positions.size());
}

glm::mat4 Renderer::viewMatrix(const Camera& camera) { return glm::lookAt(camera.eye, camera.target, camera.up); }

glm::mat4 Renderer::projectionMatrix(const Camera& camera, float aspect, float sceneRadius) {
  const float distance = glm::length(camera.eye - camera.target);
  const float nearPlane = std::max(0.01f, distance - 2.0f * sceneRadius);
  const float farPlane = distance + 4.0f * sceneRadius + 1.0f;
  return glm::perspective(camera.verticalFov, aspect, nearPlane, farPlane);
}

void Renderer::draw(const Camera& camera, int width, int height, bool particles) {
  glViewport(0, 0, width, height);
  glDisable(GL_BLEND);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);
  glDepthMask(GL_TRUE);
  glClear(GL_DEPTH_BUFFER_BIT);  // the background below covers every pixel's colour

  // Background gradient, behind everything.
  glDisable(GL_DEPTH_TEST);
  glUseProgram(backgroundProgram_);
  glUniform3fv(glGetUniformLocation(backgroundProgram_, "uTop"), 1, glm::value_ptr(look_.backgroundTop));
  glUniform3fv(glGetUniformLocation(backgroundProgram_, "uBottom"), 1, glm::value_ptr(look_.backgroundBottom));
  glBindVertexArray(backgroundVao_);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);

  const glm::mat4 view = viewMatrix(camera);
  const glm::mat4 projection =
      projectionMatrix(camera, static_cast<float>(width) / static_cast<float>(std::max(1, height)), sceneRadius_);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  if (indexCount_ > 0) {
    glUseProgram(meshProgram_);
    setMatrices(meshProgram_, view, projection);
    const glm::vec3 light = glm::normalize(look_.lightDirection);
    glUniform3fv(glGetUniformLocation(meshProgram_, "uLight"), 1, glm::value_ptr(light));
    glUniform1f(glGetUniformLocation(meshProgram_, "uAmbient"), look_.ambient);
    glUniform1f(glGetUniformLocation(meshProgram_, "uRim"), look_.rim);
    glUniform1i(glGetUniformLocation(meshProgram_, "uHasNormals"), meshHasNormals_ ? 1 : 0);
    glBindVertexArray(meshVao_);
    if (!meshHasColors_) glVertexAttrib3fv(2, glm::value_ptr(look_.defaultColor));
    glDrawElements(GL_TRIANGLES, indexCount_, GL_UNSIGNED_INT, nullptr);
  }
  if (particles && pointCount_ > 0) {
    glEnable(GL_PROGRAM_POINT_SIZE);
    glUseProgram(pointProgram_);
    setMatrices(pointProgram_, view, projection);
    glUniform1f(glGetUniformLocation(pointProgram_, "uPointSize"),
                pointSize_ > 0.0f ? pointSize_ : height >= 600 ? 4.0f : 3.0f);
    glBindVertexArray(pointVao_);
    glDrawArrays(GL_POINTS, 0, pointCount_);
  }
  glBindVertexArray(0);
  glUseProgram(0);
}

void Renderer::drawOverlay(std::span<const OverlayVertex> triangles, int width, int height) {
  if (triangles.empty()) return;
  glViewport(0, 0, width, height);
  glDisable(GL_DEPTH_TEST);
  glUseProgram(overlayProgram_);
  glUniform2f(glGetUniformLocation(overlayProgram_, "uWindow"), float(std::max(1, width)), float(std::max(1, height)));
  glBindVertexArray(overlayVao_);
  orphanAndFill(GL_ARRAY_BUFFER, overlayBuffer_, triangles.data(), triangles.size_bytes());
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(triangles.size()));
  glBindVertexArray(0);
  glUseProgram(0);
}

std::vector<uint8_t> Renderer::readPixels(int width, int height) {
  const size_t rowBytes = static_cast<size_t>(width) * 4;
  std::vector<uint8_t> pixels(rowBytes * static_cast<size_t>(height));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  // GL's rows start at the bottom.
  std::vector<uint8_t> row(rowBytes);
  for (size_t y = 0; y < static_cast<size_t>(height) / 2; ++y) {
    uint8_t* a = pixels.data() + y * rowBytes;
    uint8_t* b = pixels.data() + (static_cast<size_t>(height) - 1 - y) * rowBytes;
    std::memcpy(row.data(), a, rowBytes);
    std::memcpy(a, b, rowBytes);
    std::memcpy(b, row.data(), rowBytes);
  }
  for (size_t i = 3; i < pixels.size(); i += 4) pixels[i] = 255;
  return pixels;
}

}  // namespace imps::app
