// expect: 3:31 expected ')' to close
void main() {
    float a = (1.0 + 2.0 * 3.0;
}
