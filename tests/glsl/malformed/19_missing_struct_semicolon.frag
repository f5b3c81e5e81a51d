// expect: 5:1 expected ';' after declaration
struct S {
    float a;
} s
void main() {}
