// expect: 3:13 invalid octal
void main() {
    int a = 0789;
}
