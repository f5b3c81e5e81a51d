// expect: 3:5 reserved word
void main() {
    goto end;
}
