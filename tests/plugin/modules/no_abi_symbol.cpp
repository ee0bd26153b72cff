// A shared module that is not an rkhs-study plugin.
extern "C" [[gnu::visibility("default")]] int not_an_rkhs_plugin() {
  return 42;
}
