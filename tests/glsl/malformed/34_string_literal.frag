// expect: 3:13 unexpected character
void main() {
    int a = "text";
}
