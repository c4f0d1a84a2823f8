// mfrender — entry point (everything else lives in the mfhost library).
#include "cli.h"

int main(int argc, char** argv) { return mf::mfrender_main(argc, argv); }
