// The program of each link check (core/CMakeLists.txt): it runs nothing. Linking it with the whole
// of one folder's library and only what that library links is the check.
int main() {
  return 0;
}
