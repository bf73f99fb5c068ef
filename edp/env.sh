# Source this to run FreeFEM by hand the way the driver does: `. edp/env.sh; mpirun -np 1 FreeFem++-mpi -nw -v 0 edp/solve-2d.edp ...`
_wendel_root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export FF_INCLUDEPATH="/usr/include/freefem++/idp;$_wendel_root/edp"
export FF_LOADPATH="$_wendel_root/build/plugins;/usr/lib/freefem++/mpi"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_pml=ob1 OMPI_MCA_btl=self,vader
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
