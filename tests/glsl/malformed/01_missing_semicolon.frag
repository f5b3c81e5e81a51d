// expect: 4:5 expected ';' after declaration
void main() {
    float a = 1.0
    float b = 2.0;
}
