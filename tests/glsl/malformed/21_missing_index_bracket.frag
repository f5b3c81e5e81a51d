// expect: 4:14 expected ']' after the index
uniform float w[4];
void main() {
    w[0 = 1.0;
}
