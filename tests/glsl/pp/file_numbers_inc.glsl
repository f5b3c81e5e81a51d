int included = __FILE__;
int line_in_included = __LINE__;
