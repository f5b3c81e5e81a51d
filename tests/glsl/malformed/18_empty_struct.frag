// expect: 2:12 a struct needs at least one member
struct S { };
void main() {}
