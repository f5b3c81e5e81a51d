// expect: 5:15 cannot initialize 'x' of type 'float' with a value of type 'int'
#version 100
precision mediump float;
void main() {
    float x = 1;
    gl_FragColor = vec4(x);
}
