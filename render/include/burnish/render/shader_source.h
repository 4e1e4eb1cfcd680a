// The GLSL sources of resources/shaders/, embedded in the binary at build time, and their
// assembly into one compilable string: `#version`, then the injected `#define`s, then the file
// with its `#include "name.glsl"` lines expanded (each file once; a `#line` directive after each
// splice so compiler messages give the right file and line).
#pragma once

#include <burnish/core/util/result.h>

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace burnish::render {

/// Name/value pairs injected as `#define NAME VALUE` right after `#version`, in this order.
using ShaderDefines = std::vector<std::pair<std::string, std::string>>;

/// The embedded file `name` ("brdf_ndf.glsl", "material.frag"), or nothing.
std::optional<std::string_view> shaderSource(std::string_view name);

/// Names of every embedded shader file, sorted.
std::vector<std::string> shaderSourceNames();

/// Assembles `name` for compilation: "#version 330 core", the defines, then the file with its
/// includes expanded. Errors: unknown file, unknown include (naming the including file and
/// line), an include cycle. Files included twice are spliced once.
Result<std::string> assembleShader(std::string_view name, const ShaderDefines& defines = {});

} // namespace burnish::render
