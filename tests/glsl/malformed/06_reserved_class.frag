// expect: 2:1 reserved word
class Foo;
void main() {}
