#include "ff++.hpp"
static void Load_Init() {}
LOADFUNC(Load_Init)
