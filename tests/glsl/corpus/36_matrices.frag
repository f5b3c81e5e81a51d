#version 330 core
uniform mat4 u_viewMatrix;
uniform mat3 u_normalMatrix;
uniform mat2x3 u_skew;
in vec3 v_normal;
in vec4 v_position;
out vec4 fragColor;

mat3 rotateY(float a) {
    float c = cos(a), s = sin(a);
    return mat3(c, 0.0, -s,
                0.0, 1.0, 0.0,
                s, 0.0, c);
}

void main() {
    vec3 n = normalize(u_normalMatrix * v_normal);
    vec4 vp = u_viewMatrix * v_position;
    mat4x4 m = mat4(1.0);
    m[3].xyz = vec3(0.1);
    mat3x3 r = rotateY(0.5) * mat3(m);
    vec3 skewed = u_skew * vec2(1.0, 0.5);
    fragColor = vec4(r * n * 0.5 + 0.5 + skewed * 0.01, 1.0) + vp * 0.0;
    fragColor.a = transpose(r)[2][2];
}
