// expect: 3:20 expected an expression, found ';'
void main() {
    float a = 1.0 +;
}
