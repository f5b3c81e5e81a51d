// expect: 6:18 mixes component sets
#version 330
uniform vec4 v;
out vec4 color;
void main() {
    color = vec4(v.xg, 0.0, 1.0);
}
