// motorlab stub of the FTC SDK API (written from its public signatures; no SDK code). Compile-time only:
// on a robot the real SDK class is used. See docs/ftc-robot.md.
package com.qualcomm.hardware.lynx;

import com.qualcomm.robotcore.hardware.HardwareDevice;

/**
 * Stub of a REV Control/Expansion Hub: only the bulk-caching API. A test subclass overrides
 * clearBulkCache() to know when the next read must fetch fresh bulk data.
 */
public class LynxModule implements HardwareDevice {
    public enum BulkCachingMode { OFF, MANUAL, AUTO }

    protected BulkCachingMode bulkCachingMode = BulkCachingMode.OFF;
    private final int moduleAddress;
    private final boolean isParent;

    public LynxModule(LynxUsbDevice lynxUsbDevice, int moduleAddress, boolean isParent, boolean isUserModule) {
        this.moduleAddress = moduleAddress;
        this.isParent = isParent;
    }

    public BulkCachingMode getBulkCachingMode() {
        return bulkCachingMode;
    }

    public void setBulkCachingMode(BulkCachingMode mode) {
        if (mode == BulkCachingMode.OFF) {
            clearBulkCache();
        }
        bulkCachingMode = mode;
    }

    public void clearBulkCache() {
    }

    public int getModuleAddress() {
        return moduleAddress;
    }

    public boolean isParent() {
        return isParent;
    }

    @Override
    public Manufacturer getManufacturer() {
        return Manufacturer.Lynx;
    }

    @Override
    public String getDeviceName() {
        return "REV Hub";
    }

    @Override
    public String getConnectionInfo() {
        return "module " + moduleAddress;
    }

    @Override
    public int getVersion() {
        return 1;
    }

    @Override
    public void resetDeviceConfigurationForOpMode() {
    }

    @Override
    public void close() {
    }
}
