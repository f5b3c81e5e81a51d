// ERROR 3:7 unterminated /* comment
float a;
float /* this never ends
float b;
