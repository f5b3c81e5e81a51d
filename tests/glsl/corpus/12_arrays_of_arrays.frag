#version 430 core
layout(location = 0) out vec4 fragColor;
uniform vec2 u_resolution;

const float grid[2][3] = float[2][3](float[3](0.1, 0.2, 0.3), float[3](0.4, 0.5, 0.6));

float pick(int row, int col) {
    float local[2][3] = grid;
    float[3] rows[2] = grid;
    return local[row][col] + rows[row][col] * 0.0;
}

void main() {
    ivec2 cell = ivec2(gl_FragCoord.xy) % ivec2(3, 2);
    float v = pick(cell.y, cell.x);
    int n = grid.length() * grid[0].length();
    fragColor = vec4(vec3(v), float(n) / 6.0);
}
