// expect: 3:16 expected a field name after '.', found '('
void main() {
    vec2 a = b.(x);
}
