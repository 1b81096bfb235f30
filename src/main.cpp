#include "src/app/cli.hpp"

int main(int argc, char** argv) { return sd::app::run_cli(argc, argv); }
