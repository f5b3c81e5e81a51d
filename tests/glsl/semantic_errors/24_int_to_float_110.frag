// expect: 3:5 cannot assign a value of type 'int' to 'float'
void main() { float x;
    x = 2;
    gl_FragColor = vec4(x);
}
