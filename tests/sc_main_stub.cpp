// libsystemc.so refers to sc_main from its own main(); the test binaries use GoogleTest's main
// and call sc_start() directly, so this definition is never called.
extern "C" int sc_main(int, char**) { return 0; }
