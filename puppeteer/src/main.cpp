// The `puppeteer` program: every command of the product's command line.
#include "cli.h"

int main(int argc, char** argv) { return imps::app::runCli(argc, argv); }
