// expect: 3:28 expected ',' or ')' in the argument list
void main() {
    vec2 a = vec2(1.0, 2.0 3.0);
}
