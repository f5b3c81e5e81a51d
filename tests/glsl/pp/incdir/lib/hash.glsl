#pragma once_guard_not_supported
#define HASH(p) fract(sin(dot(p, vec2(12.9898, 78.233))) * 43758.5453)
