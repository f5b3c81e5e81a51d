// Ambient occlusion from a few spheres, after the chess shader of Sitthi-amorn et al. 2008 with
// its pieces as spheres: a const table of sphere centres and radii, one of which (the fourth)
// moves with u_moverOffset, keyframed in the session. Every sphere adds its occlusion to one sum;
// the static spheres' part of it does not change from frame to frame, and once the terms are
// reordered (the moving sphere last) it is a node of its own.
#version 330
in vec4 v_position;
in vec3 v_normal;
uniform vec3 u_moverOffset;   // where the moving sphere is this frame
uniform vec3 u_light;
out vec4 fragColor;

const int SPHERES = 7;
const int MOVER = 3;
const vec4 SPHERE[SPHERES] = vec4[](
    vec4( 1.6,  0.2,  0.0, 0.35), vec4(-1.6,  0.1,  0.3, 0.40), vec4( 0.0,  1.2,  0.8, 0.30),
    vec4( 0.3, -0.2,  1.7, 0.45), vec4(-0.5, -1.3, -0.4, 0.35), vec4( 1.1, -0.9, -1.2, 0.30),
    vec4(-1.0,  1.0, -1.1, 0.40));

// Occlusion of a receiver at p (normal n) by a sphere (centre c, radius r): the sphere's solid
// angle times its cosine over the hemisphere (Quilez's sphere occlusion).
float sphereOcclusion(vec3 p, vec3 n, vec3 c, float r) {
    vec3 d = c - p;
    float l = length(d);
    float cosine = dot(n, d / l);
    return clamp(cosine, 0.0, 1.0) * (r * r) / (l * l);
}

void main() {
    vec3 p = v_position.xyz;
    vec3 n = normalize(v_normal);
    float occlusion = 0.0;
    for (int i = 0; i < SPHERES; i++) {
        vec3 centre = SPHERE[i].xyz;
        if (i == MOVER) {
            centre += u_moverOffset;
        }
        occlusion += sphereOcclusion(p, n, centre, SPHERE[i].w);
    }
    float ao = 1.0 - clamp(occlusion, 0.0, 1.0);
    float diffuse = max(dot(n, normalize(u_light - p)), 0.0);
    fragColor = vec4(vec3(0.8, 0.75, 0.7) * ao * (0.25 + 0.75 * diffuse), 1.0);
}
