// expect: 4:1 expected ';' after expression
void main() {
    gl_FragColor = vec4(1.0)
}
