// expect: 3:5 'else' without a matching 'if'
void main() {
    else { }
}
