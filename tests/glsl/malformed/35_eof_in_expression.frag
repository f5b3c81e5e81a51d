// expect: 3:20 expected an expression, found end of file
void main() {
    float a = 1.0 *
