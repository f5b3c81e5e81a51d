// expect: 4:30 expected '}' to close the block, found end of file
void main() {
    float a = 1.0;
    if (a > 0.0) { a = 2.0; }
