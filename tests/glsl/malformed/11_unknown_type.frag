// expect: 2:9 unknown type name 'Foo'
uniform Foo bar;
void main() {}
