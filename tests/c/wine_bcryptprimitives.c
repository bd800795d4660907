/* wine_bcryptprimitives.c: bcryptprimitives.dll for Wine releases that lack it (Debian 12's
 * Wine 8.0), for python/tests/test_fmu_win64.py only; never shipped in the FMU.
 *
 * Rust's standard library on Windows draws the random seeds of its hash maps from
 * ProcessPrng in bcryptprimitives.dll, which every Windows 10 and later has. This stand-in
 * exports the one function with the same contract (fill the buffer with random bytes, return
 * TRUE) on top of RtlGenRandom (advapi32's SystemFunction036), which Wine provides. It is
 * placed beside the test harness only when Wine has no bcryptprimitives.dll of its own.
 */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    while (length > 0) {
        ULONG chunk = length > 0x40000000 ? 0x40000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk)) {
            return FALSE;
        }
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
