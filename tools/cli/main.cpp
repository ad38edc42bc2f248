#include "cullide/error.h"
#include <cstdio>
int main() { std::puts("cullide: under construction"); return 0; }
