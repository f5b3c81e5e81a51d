#version 330
// Ambient occlusion on a chess scene, after Bunnell, "Dynamic Ambient Occlusion and Indirect
// Lighting" (GPU Gems 2, chapter 14), as used in Sitthi-amorn et al. 2008, section 5.3.
//
// The scene's surfaces are approximated by discs (position, normal, area). For each pixel the
// shader sums the element-to-receiver form-factor approximation of every disc. The discs of the
// board and the static pieces live in u_discs; the discs of the king, the only piece that moves,
// live in u_kingDiscs (in the king's object space) and are moved by u_kingOffset, which follows
// the king object's keyframed translation. The two sums are kept apart and combined
// multiplicatively, so the static part does not depend on the king at all.
//
// Disc textures (RGBA32F, two texels per disc on one row):
//   texel (0, i) = (position.xyz, area),  texel (1, i) = (normal.xyz, 0).
//
// The result modulates a diffuse texture (the board's squares, or ivory/ebony for the pieces)
// lit by one point light with a Blinn-Phong highlight.

in vec4 v_position;
in vec3 v_normal;

uniform vec3 u_camera;
uniform vec3 u_light;
uniform vec3 u_lightColor;
uniform vec2 u_resolution;
uniform mat4 u_projectionMatrix;

uniform sampler2D u_discs;        // board and static pieces, world space
uniform sampler2D u_kingDiscs;    // the king, object space
uniform int u_numDiscs;
uniform int u_numKingDiscs;
uniform vec3 u_kingOffset;        // the king's translation this frame

uniform sampler2D u_boardTexture; // squares and border of the board, wood grain
uniform float u_boardHalfSize;    // the texture spans [-u_boardHalfSize, u_boardHalfSize]^2 in xz
uniform vec3 u_lightPieceColor;
uniform vec3 u_darkPieceColor;
uniform float u_shininess;

out vec4 fragColor;

const float PI = 3.14159265;
// The receiver is lifted off its surface by this much before the sums, so the discs of its own
// surface do not shadow it.
const float RECEIVER_OFFSET = 0.02;
// Fraction of a disc's area added to the squared distance (see discOcclusion).
const float NEAR_FIELD_SOFTENING = 0.12;
// Bunnell's factor on the receiver cosine (softens the terminator of near-tangent discs).
const float RECEIVER_COSINE_GAIN = 4.0;
// Scales both occlusion sums (a single pass of Bunnell's method without his second,
// shadow-correcting pass; tuned by eye for soft, visible contact shadows).
const float OCCLUSION_GAIN = 1.6;
// Pieces stand on the board's top face at y = 0; below this height a point is the board.
const float BOARD_TOP = 0.002;
const float AMBIENT_STRENGTH = 0.55;
const float DIFFUSE_STRENGTH = 0.75;
const float SPECULAR_STRENGTH = 0.35;
const float BOARD_TEXELS_PER_UNIT = 56.9;
const float GAMMA = 2.2;

// Bunnell's approximation of the occlusion of a receiver by one disc of area `area`.
float discOcclusion(vec3 receiver, vec3 receiverNormal,
                    vec3 discPosition, vec3 discNormal, float area) {
    vec3 v = discPosition - receiver;
    float distance2 = dot(v, v);
    v *= inversesqrt(distance2 + 1e-8);
    // The disc is spread over its area: softening the squared distance by a fraction of the
    // area bounds the occlusion of a receiver right next to a disc.
    float d2 = distance2 + NEAR_FIELD_SOFTENING * area;
    float solidAngle = 1.0 - inversesqrt(1.0 + area / (PI * d2));
    float cosEmitter = clamp(dot(discNormal, -v), 0.0, 1.0);
    float cosReceiver = clamp(RECEIVER_COSINE_GAIN * dot(receiverNormal, v), 0.0, 1.0);
    return solidAngle * cosEmitter * cosReceiver;
}

// Occlusion by the static discs (board and every piece but the king).
float staticOcclusion(vec3 receiver, vec3 receiverNormal) {
    float occlusion = 0.0;
    for (int i = 0; i < u_numDiscs; i++) {
        vec4 positionArea = texelFetch(u_discs, ivec2(0, i), 0);
        vec3 normal = texelFetch(u_discs, ivec2(1, i), 0).xyz;
        occlusion += discOcclusion(receiver, receiverNormal, positionArea.xyz, normal,
                                   positionArea.w);
    }
    return occlusion;
}

// Occlusion by the king's discs, moved to where the king is this frame.
float kingOcclusion(vec3 receiver, vec3 receiverNormal, vec3 kingOffset) {
    float occlusion = 0.0;
    for (int i = 0; i < u_numKingDiscs; i++) {
        vec4 positionArea = texelFetch(u_kingDiscs, ivec2(0, i), 0);
        vec3 normal = texelFetch(u_kingDiscs, ivec2(1, i), 0).xyz;
        occlusion += discOcclusion(receiver, receiverNormal, positionArea.xyz + kingOffset,
                                   normal, positionArea.w);
    }
    return occlusion;
}

// Level of detail of the board texture from the pixel footprint at this distance.
float boardLod(vec3 position) {
    float pixelAngle = 2.0 / (u_projectionMatrix[1][1] * u_resolution.y);
    float footprint = distance(u_camera, position) * pixelAngle * BOARD_TEXELS_PER_UNIT;
    return log2(max(footprint, 1.0));
}

// Diffuse colour: the board texture on the board, ivory on white's half, ebony on black's.
vec3 surfaceAlbedo(vec3 position) {
    vec2 uv = position.xz / (2.0 * u_boardHalfSize) + 0.5;
    vec3 board = textureLod(u_boardTexture, uv, boardLod(position)).rgb;
    board = pow(board, vec3(GAMMA));   // the texture is sRGB-ish, shade in linear
    vec3 piece = position.z > 0.0 ? u_lightPieceColor : u_darkPieceColor;
    return position.y < BOARD_TOP ? board : piece;
}

void main() {
    vec3 P = v_position.xyz;
    vec3 N = normalize(v_normal);
    vec3 receiver = P + N * RECEIVER_OFFSET;

    float aoStatic = 1.0 - clamp(OCCLUSION_GAIN * staticOcclusion(receiver, N), 0.0, 1.0);
    float aoKing = 1.0 - clamp(OCCLUSION_GAIN * kingOcclusion(receiver, N, u_kingOffset), 0.0, 1.0);
    float ambientOcclusion = aoStatic * aoKing;

    vec3 albedo = surfaceAlbedo(P);
    vec3 L = normalize(u_light - P);
    vec3 V = normalize(u_camera - P);
    vec3 H = normalize(L + V);
    float diffuse = max(dot(N, L), 0.0);
    float specular = pow(max(dot(N, H), 0.0), u_shininess);

    vec3 color = albedo * ambientOcclusion * (AMBIENT_STRENGTH + DIFFUSE_STRENGTH * diffuse * u_lightColor)
               + SPECULAR_STRENGTH * specular * ambientOcclusion * u_lightColor;
    fragColor = vec4(pow(color, vec3(1.0 / GAMMA)), 1.0);
}
