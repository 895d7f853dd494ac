// spec2fab-read-mesh: reads one mesh file with Assimp for load_mesh, in a
// process of its own (geometry/mesh_io.h says why). Not a command for users.
#include "geometry/mesh_io.h"

int main(int argc, char** argv) { spec2fab::mesh_reader_main(argc, argv); }
