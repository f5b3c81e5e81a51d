// expect: 3:27 expected ';' after the for-loop condition
void main() {
    for (int i = 0; i < 4 i++) {}
}
