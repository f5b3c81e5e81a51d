#version 330 core
in VertexData {
    vec3 normal;
    vec2 texcoord;
    flat int objectId;
} vin;

out vec4 fragColor;

void main() {
    float stripe = mod(floor(vin.texcoord.x * 10.0) + float(vin.objectId), 2.0);
    fragColor = vec4(normalize(vin.normal) * 0.5 + 0.5, 1.0) * (0.5 + 0.5 * stripe);
}
